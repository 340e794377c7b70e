// φh storage: a stack of per-φh slices (repr/phi_h.h) as one group per slice, each written by the module
// that stores that slice (a table of any dtype). Attributes: symmetry ("none", "reciprocal" or
// "bilateral"), slices (n, 2..GridSpec::kMaxAxis); groups slice_0 .. slice_{n-1}, each with its own
// "type" attribute and that module's contents. formats/SPEC.md §3 describes it.
#include <algorithm>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/repr/phi_h.h"
#include "container/sampler.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kPhiH{"phi-h", 4};
// phih= specs ask for at most the slices the header's extents hold (repr/phi_h.h).
static_assert(PhiHBrdf::kMaxStoredDatasets == h5::kMaxExtents);

// The module storing a slice exactly (never a stack itself).
const StorageModule* slice_module(const Brdf& slice) {
    for (const StorageModule* m : storage_modules())
        if (m->type != "phi_h" && !m->needs(slice).empty()) return m;
    return nullptr;
}

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* stack = dynamic_cast<const PhiHBrdf*>(&brdf);
    if (!stack) return {};
    std::vector<Feature> out{kPhiH};
    for (const auto& slice : stack->slices()) {
        const StorageModule* m = slice_module(*slice);
        if (!m) return {};
        for (const Feature& f : m->needs(*slice))
            if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
    }
    return out;
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const auto& stack = dynamic_cast<const PhiHBrdf&>(brdf);
    rep.attr("symmetry", std::string(phi_h_symmetry_name(stack.symmetry())));
    rep.attr("slices", std::uint64_t{stack.slices().size()});
    for (std::size_t k = 0; k < stack.slices().size(); ++k) {
        const Brdf& slice = *stack.slices()[k];
        const StorageModule* m = slice_module(slice);
        h5::WriteNode g = rep.group("slice_" + std::to_string(k));
        g.attr("type", std::string(m->type));
        m->write(g, slice);
    }
    // The stack's own sampler, or "fine" when it samples its slices' (each in its group).
    write_sampler(rep, stack.sampler_kind(), stack.sampler().compact());
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext& ctx) {
    const std::string symmetry = rep.str("symmetry");
    const std::uint64_t n = rep.u64("slices");
    if (n < 2 || n > static_cast<std::uint64_t>(GridSpec::kMaxAxis))
        throw FormatError(rep.file(), rep.path() + ": attribute 'slices' is " + std::to_string(n) + ", not in 2.." +
                                          std::to_string(GridSpec::kMaxAxis));
    try {
        const PhiHSymmetry s = parse_phi_h_symmetry(symmetry);
        std::vector<std::unique_ptr<Brdf>> slices;
        for (std::uint64_t k = 0; k < n; ++k) {
            const h5::ReadNode g = rep.group("slice_" + std::to_string(k));
            const std::string type = g.str("type");
            const StorageModule* m = find_storage(type);
            if (!m || type == "phi_h")
                throw FormatError(rep.file(), g.path() + ": slice type '" + type + "' cannot be a φh slice");
            slices.push_back(m->read(g, ctx));
        }
        return with_sampler(rep, [&](auto sampler) { return std::make_unique<PhiHBrdf>(std::move(slices), s, std::move(sampler)); });
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

// The slices' own descriptions, combined: dims lead with the slice count, counts summed, one range.
void source_info(const Brdf& brdf, SourceInfo& info) {
    const auto& stack = dynamic_cast<const PhiHBrdf&>(brdf);
    SourceInfo all = info;
    all.counts = {};
    all.min_value = std::numeric_limits<double>::infinity();
    all.max_value = -all.min_value;
    for (const auto& slice : stack.slices()) {
        SourceInfo one;
        one.format = info.format;
        slice_module(*slice)->source_info(*slice, one);
        all.dims = one.dims;
        all.dims.insert(all.dims.begin(), stack.slices().size());
        all.dims_of = "φh slices x " + (one.dims_of.empty() ? std::string("the slice's grid") : one.dims_of);
        all.has_range = one.has_range;
        all.counts.valid += one.counts.valid;
        all.counts.negative += one.counts.negative;
        all.counts.nan += one.counts.nan;
        all.counts.inf += one.counts.inf;
        all.counts.clamped += one.counts.clamped;
        all.counts.below_horizon += one.counts.below_horizon;
        all.min_value = std::min(all.min_value, one.min_value);
        all.max_value = std::max(all.max_value, one.max_value);
    }
    if (!all.has_range) all.min_value = all.max_value = 0.0;
    info = all;
}

}  // namespace

void register_phi_h(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"phi_h", {kPhiH}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
