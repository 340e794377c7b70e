// Directional albedo ρ(θo) = ∫ f(wi, wo) cosθi dωi over the upper hemisphere, by deterministic
// quadrature. The integral is taken over half vectors (dωi = 4 (wo·h) dωh) on MERL's square-root θh
// axis, so a specular peak at h = ẑ is resolved; the horizon cut (wi.z = 0) is located per φh and
// the θh range integrated exactly up to it, so smooth BRDFs converge fast (1e-6 for a Lambertian).
// Interpolated tables have kinks at every bin: at the defaults, expect ~1e-3 relative on sharp
// measured data (MERL chrome), shrinking with more panels and φh nodes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "brdfz/brdf.h"

namespace brdfz {

struct AlbedoOptions {
    int n_phi = 256;    // midpoint nodes in φh
    int n_panels = 16;  // composite Gauss-Legendre panels along √θh
    int order = 8;      // nodes per panel
};

// θo in radians, [0, π/2). wo lies in the xz-plane.
Rgb directional_albedo(const Brdf& brdf, double theta_o, const AlbedoOptions& options = {});

// The same integral estimated with the Brdf's own sampler: the mean of `n` sample weights (failed
// samples count as 0) and its standard error. Deterministic for a given seed. Comparing it with
// directional_albedo checks a sampler end to end.
struct SampledAlbedo {
    Rgb mean{}, stderr_{};
};
SampledAlbedo sampled_albedo(const Brdf& brdf, double theta_o, std::size_t n, std::uint64_t seed = 1);

// How many samples the Brdf's own sampler needs for the albedo at θo, against cosine-weighted
// sampling, for the same noise: the variance of its weights over that of cosine sampling's weights
// π·f (luminance, each relative to its mean, n samples each), each floored at floor². The floor
// makes near-ideal estimators compare as equal: on a Lambertian, cosine sampling's weights are
// constant (variance 0) and a tabulated sampler's have a relative spread of ~0.05, a ratio of
// noise to nothing without it. An estimator whose relative spread is below floor = 0.1 errs by at
// most 10 % with one sample, 2.5 % with 16. Infinite when a weight is not finite; 1 when both means
// are 0. ValueError for θo outside [0, π/2), n < 2 or a negative floor.
double sampler_variance_ratio(const Brdf& brdf, double theta_o, std::size_t n, double floor = 0.1,
                              std::uint64_t seed = 1);

// How well the Brdf's own sampler matches it at θo (wo in the xz-plane): E[w²]/E[w]² of the luminance
// of the sample weights w = f·cosθi/pdf, over n draws on a stratified grid (⌈√n⌉² jittered cells of
// u; failed draws count as 0). 1 when the density is ∝ luminance(f)·cosθi; the factor by which the
// sampler needs more draws than that ideal one for the same noise. Infinite when a weight is not
// finite, 1 when every weight is 0. ValueError for θo outside [0, π/2) or n < 2.
double sampler_second_moment(const Brdf& brdf, double theta_o, std::size_t n, std::uint64_t seed = 1);

}  // namespace brdfz
