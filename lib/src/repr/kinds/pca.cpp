// Kind `pca`: k coefficients of a shared basis (repr/pca.h) learnt by `brdfz pca-train`.
#include "brdfz/errors.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace brdfz::kinds {
namespace {

Compressed build(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const std::string file = spec.get_string("basis", "");
    const int k = spec.get_int("k", 12, 1, 1 << 16);
    const Lookup lookup = lookup_option(spec);
    const bool embed = spec.get_choice("store", "reference", {"reference", "embed"}) == "embed";
    const bool confirm_symmetry = spec.has("symmetry");
    const Symmetry symmetry = symmetry_option(spec, "a PCA basis's φd axis is reciprocal or none (brdfz pca-train --symmetry)");
    const SamplerKind sampler = sampler_option(spec);
    spec.finish();
    if (file.empty()) throw ValueError("pca: name the basis file (brdfz pca-train makes one), e.g. pca:basis=merl.brdfz,k=12");
    if (!options.load_pca_basis)
        throw ValueError("pca: basis files are read through brdfz::formats (CompressOptions::load_pca_basis is unset)");
    std::shared_ptr<const PcaBasis> basis = options.load_pca_basis(file);
    // The basis fixes the grid, its φd axis included: the key can only confirm it.
    if (confirm_symmetry && symmetry != basis->grid().symmetry)
        throw ValueError("pca: symmetry=" + std::string(symmetry_name(symmetry)) + " but basis " + file + " has symmetry " +
                         symmetry_name(basis->grid().symmetry) + " (brdfz pca-train --symmetry)");
    if (k > basis->k_max())
        throw ValueError("pca: k = " + std::to_string(k) + " but basis " + file + " has " +
                         std::to_string(basis->k_max()) + " components");
    Compressed out;
    // Projection needs the source on the basis's grid: a table already there is used as it is.
    const Table* table = source.stored_table();
    std::optional<Tabulated> tabulated;
    if (!table || !(table->grid() == basis->grid())) {
        TabulateOptions tab;
        tab.grid = basis->grid();
        tab.threads = options.threads;
        tab.progress = options.progress;
        tabulated = tabulate_noted(source, tab, out);
    }
    const Table& values = tabulated ? tabulated->table : *table;
    auto pca = std::make_unique<PcaBrdf>(basis, basis->project(values, k), lookup,
                                         embed ? PcaBrdf::BasisStorage::Embedded : PcaBrdf::BasisStorage::Referenced,
                                         sampler);
    if (pca->counts().clamped > 0)
        out.notes.push_back(std::to_string(pca->counts().clamped) + " reconstructed bins with negative values clamped to 0");
    out.brdf = std::move(pca);
    return out;
}

}  // namespace

void register_pca(std::vector<ReprKind>& out) {
    out.push_back({"pca",
                   "k coefficients of a basis learnt by brdfz pca-train, referenced by its content hash or embedded",
                   "",
                   {{"basis", "(required)", "the basis file (.brdfz)"},
                    {"k", "12", "coefficients kept, at most the basis's components"},
                    {"store", "reference", "reference|embed: refer to the basis file or embed the basis"},
                    kLookupKey,
                    {"symmetry", "(the basis's)", "reciprocal|none: must be the basis's φd axis (brdfz pca-train --symmetry)"},
                    kSamplerKey},
                   build});
}

}  // namespace brdfz::kinds
