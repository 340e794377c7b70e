// Sampling a Rusinkiewicz table together with its weight (TabularBrdf, CompactTableBrdf): the
// half-vector sampler draws h by its angles relative to wo, and the lookup of f(wi, wo) needs the
// pair's (θh, θd, φd). θd and φd are the angles of wi in h's frame, a rotation of wo = (sinθo, 0, cosθo)
// by the drawn angles, so no half vector, cross product or normalisation is rebuilt from wi and wo.
// Draws from the cosine share carry no angles and take fast_bin_coords.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

#include "brdfz/sample/halfvector.h"
#include "detail/table_lookup.h"

namespace brdfz::detail {

// fast_bin_coords(g, wi, wo) for a half-vector draw (d.half), from its angles. In h's frame
// (half_frame's t, b, h) wi = reflect(wo, h) is the mirror of wo: (−wo·t, −wo·b, wo·h), with
// wo·t = sinθo cosφ cosθh − cosθo sinθh and wo·b = −sinθo sinφ. The coordinates agree with
// fast_bin_coords' to ~5e-12 bins in θh and θd (the same polynomial arctangent of the same ratios) and
// in φd to ~1e-12 bins / (sinθh sinθd), its conditioning in fast_bin_coords (tests/lib/sample_test.cpp);
// φd is flagged ill-conditioned where fast_bin_coords flags it (θh or θd below 1e-6).
[[gnu::always_inline]] inline BinCoords drawn_bin_coords(const GridSpec& g, double sin_h, double cos_h, double sin_p,
                                                        double cos_p, double sin_o, double cos_o) {
    const double a = sin_o * cos_p;
    const double dx = cos_o * sin_h - a * cos_h, dy = sin_o * sin_p, dz = a * sin_h + cos_o * cos_h;
    const double sin_d = std::sqrt(dx * dx + dy * dy);
    const double theta_d = fast_half_turn_angle(sin_d, dz);
    // θh through the same arctangent as fast_bin_coords rather than the drawn y: the polynomial's error
    // (up to 6e-11 relative) is then the same in both, where y·n differs from eval's coordinate by up
    // to ~4e-9 bins, which moved the weight 6e-9 (relative) off eval's on a glossy table.
    const double theta_h = fast_half_turn_angle(sin_h, cos_h);
    constexpr double kMinSin = 1e-6;
    const bool sure = (sin_h > kMinSin) & (sin_d > kMinSin);
    const double up = phi_d_coord(g, dy, dx);
    // dz is cosθd: wi is a unit vector in h's frame.
    return {theta_h_coord(g, theta_h), theta_d_coord(g, theta_d, dz),
            std::max(up, sure ? 0.0 : kIllConditioned)};
}

inline BinCoords drawn_bin_coords(const GridSpec& g, const HalfVectorSampler::Draw& d) {
    return drawn_bin_coords(g, d.sin_h, d.cos_h, d.sin_p, d.cos_p, d.sin_o, d.cos_o);
}

// The bin coordinates of a draw's pair (d.sample.pdf > 0).
inline BinCoords draw_bin_coords(const GridSpec& g, const HalfVectorSampler::Draw& d, const Vec3& wo) {
    return d.half ? drawn_bin_coords(g, d) : fast_bin_coords(g, d.sample.wi, wo);
}

// One division per sample, not one per channel: the kernels are short enough for three to show.
inline void set_weight(BrdfSample& s, const Rgb& f) {
    const double c = s.wi.z / s.pdf;
    for (int ch = 0; ch < 3; ++ch) s.weight[ch] = f[ch] * c;
}

// One sample with its weight, for wo above the horizon and u in [0, 1)² (Brdf::sample_above).
template <typename Blend, typename Values>
[[gnu::always_inline]] inline BrdfSample sample_one(const GridSpec& g, const Values& values, Lookup lookup,
                                                    const HalfVectorSampler& sampler, const Vec3& wo, double u1,
                                                    double u2) {
    const HalfVectorSampler::Draw d = sampler.draw(wo, u1, u2);
    BrdfSample s = d.sample;
    if (!Brdf::usable(s)) return {};
    const BinCoords c = draw_bin_coords(g, d, wo);
    set_weight(s, lookup == Lookup::Nearest ? read_nearest(values, nearest_bin(g, c, s.wi, wo))
                                            : read_linear<Blend>(g, values, linear_corners(g, c, s.wi, wo)));
    return s;
}

// Brdf::sample_batch: blocks of draws in passes, as eval_table_batch does for pairs: (1) the draws
// (HalfVectorSampler::draw_block), (2) their bin coordinates, (3) the table reads (lookup_block) and the
// weights. Each result is sample_table's, bit for bit.
template <typename Blend, typename Values>
[[gnu::always_inline]] inline void sample_table_passes(const GridSpec& g, const Values& values, Lookup lookup,
                                                       const HalfVectorSampler& sampler, const Vec3* wo,
                                                       const std::array<double, 2>* u, BrdfSample* out,
                                                       std::size_t n) {
    constexpr std::size_t kBlock = HalfVectorSampler::kBlock;
    static_assert(kBlock <= kLookupBlock);
    HalfVectorSampler::Draws d;
    BlockCoords coords;
    bool ok[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        BrdfSample* s = out + start;
        const Vec3* w = wo + start;
        sampler.draw_block(w, u + start, m, d);
        for (std::size_t k = 0; k < m; ++k)
            ok[k] = Brdf::usable({{d.wi_x[k], d.wi_y[k], d.wi_z[k]}, d.pdf[k], {}});
        // Every draw's angles, set or not (unset ones are zeros, whose coordinates are not used).
        for (std::size_t k = 0; k < m; ++k)
            coords.set(k, drawn_bin_coords(g, d.sin_h[k], d.cos_h[k], d.sin_p[k], d.cos_p[k], d.sin_o[k], d.cos_o[k]));
        const auto wi = [&d](std::size_t k) { return Vec3{d.wi_x[k], d.wi_y[k], d.wi_z[k]}; };
        for (std::size_t k = 0; k < m; ++k)
            if (ok[k] && !d.half[k]) coords.set(k, fast_bin_coords(g, wi(k), w[k]));
        // Each sample is written once, whole, with its weight.
        lookup_block<Blend>(g, values, lookup, coords, ok, m, wi, w, [s, &d, &wi](std::size_t k, const Rgb& f) {
            s[k] = {wi(k), d.pdf[k], {}};
            set_weight(s[k], f);
        });
        for (std::size_t k = 0; k < m; ++k)
            if (!ok[k]) s[k] = {};
    }
}

}  // namespace brdfz::detail
