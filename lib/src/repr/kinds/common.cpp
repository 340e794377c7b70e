#include "common.h"

#include <algorithm>
#include <cstdio>
#include <numbers>

#include "brdfz/errors.h"

namespace brdfz::kinds {

void note_tabulation(const Brdf& source, const Tabulated& t, Compressed& out) {
    if (t.counts.clamped > 0)
        out.notes.push_back(std::to_string(t.counts.clamped) + " negative values clamped to 0 when tabulating");
    if (t.extrapolated > 0) {
        char deg[32];
        std::snprintf(deg, sizeof deg, "%.2f", source.measured_theta_max() * 180.0 / std::numbers::pi);
        out.notes.push_back(std::to_string(t.extrapolated) + " samples beyond the measured elevation (" + deg +
                            " deg) taken at it");
    }
}

Lookup lookup_option(const ReprSpec& spec) {
    return parse_lookup(spec.get_choice("lookup", "linear", {"linear", "nearest"}));
}

double theta_d_warp_option(const ReprSpec& spec) {
    const double w = spec.get_double("dwarp", 0.0);
    if (!(w >= 0.0 && w <= GridSpec::kMaxWarp))
        throw ValueError(spec.kind() + ": dwarp=" + spec.get_string("dwarp", "") + " is outside [0, 0.95]");
    return w;
}

Symmetry symmetry_option(const ReprSpec& spec, const std::string& why_not, Symmetry fallback) {
    if (spec.get_string("symmetry", "") == "bilateral")
        throw ValueError(spec.kind() + ": symmetry=bilateral folds φd by the mirror, but " + why_not +
                         ": use reciprocal or none");
    return parse_symmetry(spec.get_choice("symmetry", symmetry_name(fallback), {"reciprocal", "none"}));
}

std::string phi_h_symmetry_option(const ReprSpec& spec, Symmetry fallback) {
    return spec.get_choice("symmetry", symmetry_name(fallback), {"reciprocal", "none", "bilateral"});
}

SamplerKind sampler_option(const ReprSpec& spec) {
    return parse_sampler_kind(spec.get_choice("sampler", "compact", {"compact", "fine"}));
}

Compressed build_phi_h(const Brdf& source, int n, PhiHSymmetry symmetry, SamplerKind sampler,
                       const std::function<Compressed(const Brdf&, Symmetry, SamplerKind)>& build_slice) {
    Compressed out;
    const SamplerKind slices = sampler == SamplerKind::Fine ? SamplerKind::Fine : SamplerKind::None;
    out.brdf = tabulate_phi_h(source, n, symmetry, [&](const Brdf& slice) {
        Compressed c = build_slice(slice, slice_symmetry(symmetry), slices);
        for (std::string& note : c.notes)
            if (std::find(out.notes.begin(), out.notes.end(), note) == out.notes.end()) out.notes.push_back(std::move(note));
        return std::move(c.brdf);
    }, sampler);
    return out;
}

TabulateOptions::FitWeight weight_option(const ReprSpec& spec, bool lsq) {
    if (!lsq && spec.has("weight")) throw ValueError(spec.kind() + ": weight= belongs to the least-squares fit (lsq)");
    return spec.get_choice("weight", "bins", {"bins", "solid"}) == "solid" ? TabulateOptions::FitWeight::SolidAngle
                                                                           : TabulateOptions::FitWeight::Bins;
}

Tabulated tabulate_noted(const Brdf& source, const TabulateOptions& tab, Compressed& out) {
    tab.grid.validate();
    Tabulated t = tabulate(source, tab);
    note_tabulation(source, t, out);
    return t;
}

}  // namespace brdfz::kinds
