#include "common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <tuple>
#include <vector>

#include "brdfz/coords.h"
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

double specular_peak_half_width(const Brdf& source) {
    constexpr double kDeg = std::numbers::pi / 180.0;
    // θh on a square-root spacing to 30° (steps of 0.02° at 0.5°); φd round the whole circle, so that a
    // non-reciprocal source's two sides both count.
    constexpr int kThetaH = 400, kPhiD = 16;
    constexpr double kThetaHMax = 30.0 * kDeg;
    std::vector<Vec3> wi(kThetaH * kPhiD), wo(kThetaH * kPhiD);
    std::vector<Rgb> f(wi.size());
    std::vector<double> widths;
    for (const double theta_d : {10.0, 20.0, 30.0, 40.0, 50.0, 60.0}) {
        for (int j = 0; j < kThetaH; ++j)
            for (int p = 0; p < kPhiD; ++p) {
                const double t = static_cast<double>(j) / (kThetaH - 1);
                std::tie(wi[j * kPhiD + p], wo[j * kPhiD + p]) =
                    from_half_diff({t * t * kThetaHMax, 0.0, theta_d * kDeg, (p + 0.5) * 2.0 * std::numbers::pi / kPhiD});
            }
        source.eval(wi, wo, f);
        std::vector<double> v(kThetaH, 0.0);
        for (int j = 0; j < kThetaH; ++j)
            for (int p = 0; p < kPhiD; ++p) {
                const Rgb& x = f[j * kPhiD + p];
                const double y = 0.2126 * x[0] + 0.7152 * x[1] + 0.0722 * x[2];
                v[j] += std::isfinite(y) ? y / kPhiD : 0.0;
            }
        const int top = static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
        const double base = v.back(), half = 0.5 * (v[top] + base);
        if (!(v[top] > 2.0 * base) || !(base >= 0.0)) continue;
        for (int j = top + 1; j < kThetaH; ++j)
            if (v[j] < half) {
                const double t = static_cast<double>(j) / (kThetaH - 1);
                widths.push_back(t * t * kThetaHMax);
                break;
            }
    }
    if (widths.size() < 3) return 0.0;  // a peak at half the elevations at least
    std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
    return widths[widths.size() / 2];
}

double theta_h_warp_option(const ReprSpec& spec, const Brdf& source, std::vector<std::string>& notes) {
    constexpr double kDeg = std::numbers::pi / 180.0;
    if (spec.get_string("hwarp", "0") == "auto") {
        const double width = specular_peak_half_width(source);
        char text[160];
        if (width == 0.0) {
            notes.push_back("hwarp=auto: no specular peak, the square-root θh axis");
            return 0.0;
        }
        const double s = std::clamp(kPeakHalfWidths * width, GridSpec::kMinThetaHWarp, GridSpec::kMaxThetaHWarp);
        std::snprintf(text, sizeof text, "hwarp=auto: the specular peak's half width %.3f deg, the θh axis warped at %.3f deg",
                      width / kDeg, s / kDeg);
        notes.push_back(text);
        return s;
    }
    const double d = spec.get_double("hwarp", 0.0);
    if (!(d == 0.0 || (d >= 0.01 && d <= 45.0)))
        throw ValueError(spec.kind() + ": hwarp=" + spec.get_string("hwarp", "") + " must be 0, auto or in [0.01, 45] degrees");
    return d * kDeg;
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
