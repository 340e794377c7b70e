// φh storage: a stack of per-φh slices (repr/phi_h.h) as one group per slice, each written by the module
// that stores that slice (a table of any dtype). Attributes: symmetry ("none", "reciprocal" or
// "bilateral"), slices (n, 2..GridSpec::kMaxAxis); groups slice_0 .. slice_{n-1}, each with its own
// "type" attribute and that module's contents. formats/SPEC.md §3 describes it.
#include <algorithm>

#include "brdfz/errors.h"
#include "brdfz/repr/phi_h.h"
#include "storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kPhiH{"phi-h", 4};

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
        return std::make_unique<PhiHBrdf>(std::move(slices), s);
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

}  // namespace

const StorageModule& phi_h_storage() {
    static const StorageModule m{"phi_h", {kPhiH}, &needs, &write, &read};
    return m;
}

}  // namespace brdfz::container::detail
