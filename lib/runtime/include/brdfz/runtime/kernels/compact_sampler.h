// The compact sampler: importance sampling of any isotropic BRDF from a few kilobytes, with an exact pdf.
// The one source of its draws and densities: the core's representations (sample/compact.h builds the
// tables) and brdfz::runtime both run these functions, so their draws agree to the bit.
//
// The half vector h is drawn relative to wo, in wo's azimuthal frame, from a density per unit solid
// angle of h on cells of
//   rows:    s = sin²(θh/2) between per-material edges (s_edges, 0 … ½; dωh = 2 ds dφ), placed by the
//            builder where the material's mass is, so that a specular peak gets narrow rows; within
//            a row the density is linear in s between the slice's weights at the row's edges
//            (edge_weight), so that a peak varying steeply across a row is followed there too (the
//            row's probability is its stored one: the weights only shape it within the row);
//   columns: φ = |φh − φo| uniform over [0, φmax(s, θo)], both sides of wo's plane alike (isotropy),
//            where φmax is the azimuth up to which h reflects wo above the horizon (wi.z > 0 ⟺
//            cosθo·cos2θh + sinθo·sin2θh·cosφ > 0): no draw is spent below the horizon, and a cell's
//            density does not change where the horizon crosses it.
// Slices at view directions uniform in cosθo, cosθo_k = 1 − k/(slices − 1)·(1 − cos_theta_max), so
// denser towards grazing where a lobe changes fastest: a given wo picks one of its two neighbouring
// slices at random with linear weights in cosθo. Then wi = reflect(wo, h). A share of cosine-weighted
// draws keeps the pdf positive wherever f·cosθi may be.
//
// Probabilities are fixed-point integers: a slice's rows by the upper ends of their intervals in
// units of 1/(2^32 − 1) (row_cdf, the last one 2^32 − 1), a row's columns likewise in units of
// 1/65535 (col_cdf, the last one 65535): a cell's probability is the same number wherever it is
// computed (CPU, GPU, float or double). sample() returns pdf(wo, wi) of the direction it drew.
//
//   pdf(wo, wi) = share·cosθi/π
//                 + (1 − share)·Σ_slices w_k·P_k(row)·P_k(col | row)·shape_k(τ) / (Ω_cell · 4 (wo·h))
//   Ω_cell = 4·(s_{r+1} − s_r)·φmax(s, θo)/cols,  shape_k(τ) = lerp(e_r, e_{r+1}, τ)/((e_r + e_{r+1})/2)
// at wi's own s, τ = (s − s_r)/(s_{r+1} − s_r), e the slice's edge weights.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::runtime::kernels {

// The sampler's tables, wherever they are stored (a CompactSampler's vectors, a mapped file).
struct CompactSamplerView {
    int slices = 0, rows = 0, cols = 0;   // slices ≥ 2
    double cos_theta_max = 0;             // cosθo of the last slice, in [0, 1)
    double cosine_share = 0;              // probability of a cosine-weighted draw, in (0, 1)
    const float* s_edges = nullptr;       // rows + 1, increasing, from 0 to 0.5
    const std::uint32_t* row_cdf = nullptr;  // slices × rows, each slice non-decreasing to 2^32 − 1
    const std::uint16_t* col_cdf = nullptr;  // slices × rows × cols, each row non-decreasing to 65535
    const std::uint16_t* edge_weight = nullptr;  // slices × (rows + 1): binary16 weights >= 0
};

constexpr double kRowUnits = 4294967295.0;
constexpr double kColUnits = 65535.0;

// wo's azimuth as a rotation (cos, sin), the identity at the pole, and sinθo = ‖wo_xy‖.
struct ViewFrame {
    double c, s, sin_o;
};
inline ViewFrame view_frame(const Vec3& wo) {
    const double r = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    return r > 0.0 ? ViewFrame{wo.x / r, wo.y / r, r} : ViewFrame{1.0, 0.0, 0.0};
}

// The slice below wo's elevation and the weight of the one above.
struct SlicePair {
    int k0;
    double t;
};
inline SlicePair slice_pair(const CompactSamplerView& v, double cos_o) {
    const double scaled = (1.0 - cos_o) / (1.0 - v.cos_theta_max) * (v.slices - 1);
    const double pos = scaled > 0.0 ? (scaled < v.slices - 1.0 ? scaled : v.slices - 1.0) : 0.0;  // NaN: 0
    const int k0 = std::min(static_cast<int>(pos), v.slices - 2);
    return {k0, pos - k0};
}

// The azimuth φmax in [0, π] up to which the half vector at s = sin²(θh/2) reflects wo above the horizon.
inline double valid_azimuth(double s, double sin_o, double cos_o) {
    const double q = s * (1.0 - s);
    const double a = cos_o * (1.0 - 8.0 * q), b = sin_o * 4.0 * std::sqrt(q) * (1.0 - 2.0 * s);  // cos2θh, sin2θh
    // cos φmax = −a/b; b = 0 (the pole, the normal view, θh = 90°): everything or nothing.
    const double x = b > 0.0 ? -a / b : (a > 0.0 ? -2.0 : 2.0);
    if (!(x > -1.0)) return kPi;
    if (!(x < 1.0)) return 0.0;
    return fast_half_turn_angle(std::sqrt(1.0 - x * x), x);
}

// The first i in [0, n) with x < ends[i], or n − 1 when there is none; a fixed number of steps.
template <typename T>
inline int first_above(const T* ends, int n, double x) {
    int base = 0;
    while (n > 1) {
        const int half = n / 2;
        base = static_cast<double>(ends[base + half - 1]) <= x ? base + half : base;
        n -= half;
    }
    return base;
}

// The probability of interval i of a fixed-point CDF of upper ends.
template <typename T>
inline double interval(const T* ends, int i, double units) {
    return (static_cast<double>(ends[i]) - (i > 0 ? static_cast<double>(ends[i - 1]) : 0.0)) / units;
}

// The linear shape of slice k's density across row r: its two edge weights (equal when both are 0).
struct RowShape {
    double a, b;
};
inline RowShape row_shape(const CompactSamplerView& v, int k, int r) {
    const std::uint16_t* e = v.edge_weight + static_cast<std::size_t>(k) * (v.rows + 1) + r;
    const double a = half_to_float(e[0]), b = half_to_float(e[1]);
    return a + b > 0.0 ? RowShape{a, b} : RowShape{1.0, 1.0};
}
// The density's factor at τ in [0, 1] across the row (its mean over the row is 1).
inline double shape_at(const RowShape& w, double tau) { return (w.a + (w.b - w.a) * tau) / (0.5 * (w.a + w.b)); }
// The τ whose share of the row's linear density is x in [0, 1]: the root of its quadratic CDF in the
// form without cancellation.
inline double shape_inverse(const RowShape& w, double x) {
    const double c = x * 0.5 * (w.a + w.b);
    const double root = w.a + std::sqrt(std::max(w.a * w.a + 2.0 * (w.b - w.a) * c, 0.0));
    return std::clamp(root > 0.0 ? 2.0 * c / root : x, 0.0, 1.0);
}

// The data share's density of wi per unit solid angle, for wo and wi above the horizon: 0 where it
// has none. Every index stays within the tables for any input, NaN included.
inline double compact_data_density(const CompactSamplerView& v, const Vec3& wo, const Vec3& wi) {
    const ViewFrame f = view_frame(wo);
    const Vec3 s = wi + wo;  // the half vector, unnormalised
    const double lx = f.c * s.x + f.s * s.y, ly = f.c * s.y - f.s * s.x;
    const double rxy2 = lx * lx + ly * ly, len = std::sqrt(rxy2 + s.z * s.z);
    const double sh = rxy2 / (2.0 * len * (len + s.z));  // sin²(θh/2) = (1 − cosθh)/2 without cancellation
    const int r = first_above(v.s_edges + 1, v.rows, sh);
    const double phi_max = valid_azimuth(sh, f.sin_o, wo.z);
    const double cpos = fast_half_turn_angle(std::fabs(ly), lx) / phi_max * v.cols;  // NaN at the pole
    const int c = cpos > 0.0 ? std::min(static_cast<int>(cpos), v.cols - 1) : 0;
    const SlicePair sp = slice_pair(v, wo.z);
    const double s0 = v.s_edges[r], ds = static_cast<double>(v.s_edges[r + 1]) - s0;
    const double tau = std::clamp((sh - s0) / ds, 0.0, 1.0);  // NaN for a NaN sh: then p is NaN, so 0
    double p = 0.0;
    for (int j = 0; j < 2; ++j) {
        const int k = sp.k0 + j;
        const double w = j ? sp.t : 1.0 - sp.t;
        const std::size_t row = static_cast<std::size_t>(k) * v.rows + r;
        p += w * interval(v.row_cdf + static_cast<std::size_t>(k) * v.rows, r, kRowUnits) *
             interval(v.col_cdf + row * v.cols, c, kColUnits) * shape_at(row_shape(v, k, r), tau);
    }
    const double omega = 4.0 * ds * phi_max / v.cols;
    const double wo_h = (wo.x * s.x + wo.y * s.y + wo.z * s.z) / len;
    const double density = p / (omega * 4.0 * wo_h);
    return density > 0.0 && density < std::numeric_limits<double>::infinity() ? density : 0.0;
}

// The density sample() draws from, per unit solid angle of wi, for wo and wi above the horizon.
inline double compact_pdf(const CompactSamplerView& v, const Vec3& wo, const Vec3& wi) {
    return v.cosine_share * wi.z / kPi + (1.0 - v.cosine_share) * compact_data_density(v, wo, wi);
}

struct CompactDraw {
    Vec3 wi;
    double pdf;  // 0: failed (wi below the horizon)
};

// A draw for wo above the horizon and u1, u2 in [0, 1): u1 picks the share, the slice and the row,
// u2 the side of wo's plane and the column; what remains of each places h within its cell.
inline CompactDraw compact_sample(const CompactSamplerView& v, const Vec3& wo, double u1, double u2) {
    const double share = v.cosine_share;
    const bool lower = u2 < 0.5;
    Vec3 wi;
    if (u1 < share) {
        const double e = u1 / share, r = std::sqrt(e);
        const SinCos p = sincos_half_turn(2.0 * kPi * (lower ? u2 : 1.0 - u2));
        wi = {r * p.c, r * (lower ? p.s : -p.s), std::sqrt(1.0 - e)};
    } else {
        const ViewFrame f = view_frame(wo);
        const SlicePair sp = slice_pair(v, wo.z);
        double v1 = (u1 - share) / (1.0 - share);
        const bool upper = !(v1 < 1.0 - sp.t);
        v1 = upper ? (v1 - (1.0 - sp.t)) / sp.t : v1 / (1.0 - sp.t);
        const int k = upper ? sp.k0 + 1 : sp.k0;
        const std::uint32_t* rows = v.row_cdf + static_cast<std::size_t>(k) * v.rows;
        const double x1 = v1 * kRowUnits;
        const int r = first_above(rows, v.rows, x1);
        const double lo1 = r > 0 ? rows[r - 1] : 0.0, hi1 = rows[r];
        const double fr = std::clamp(hi1 > lo1 ? (x1 - lo1) / (hi1 - lo1) : 0.5, 0.0, 1.0);
        const std::uint16_t* cols = v.col_cdf + (static_cast<std::size_t>(k) * v.rows + r) * v.cols;
        const double x2 = (lower ? 2.0 * u2 : 2.0 * u2 - 1.0) * kColUnits;
        const int c = first_above(cols, v.cols, x2);
        const double lo2 = c > 0 ? cols[c - 1] : 0.0, hi2 = cols[c];
        const double fc = std::clamp(hi2 > lo2 ? (x2 - lo2) / (hi2 - lo2) : 0.5, 0.0, 1.0);
        const double s0 = v.s_edges[r];
        const double s = s0 + shape_inverse(row_shape(v, k, r), fr) * (static_cast<double>(v.s_edges[r + 1]) - s0);
        const double sin_h = 2.0 * std::sqrt(s * (1.0 - s)), cos_h = 1.0 - 2.0 * s;
        const SinCos p = sincos_half_turn((c + fc) / v.cols * valid_azimuth(s, f.sin_o, wo.z));
        const double hx = sin_h * p.c, hy = lower ? sin_h * p.s : -sin_h * p.s;
        const Vec3 h{f.c * hx - f.s * hy, f.s * hx + f.c * hy, cos_h};
        const double d = 2.0 * (wo.x * h.x + wo.y * h.y + wo.z * h.z);
        wi = {d * h.x - wo.x, d * h.y - wo.y, d * h.z - wo.z};
    }
    if (!(wi.z > 0.0)) return {{}, 0.0};
    return {wi, compact_pdf(v, wo, wi)};
}

// Why tables cannot make a sampler, or nullptr when they can: parameters in range, edges increasing
// from 0 to ½, CDFs non-decreasing to full scale, edge weights finite and not negative. The arrays
// must hold the sizes the shape gives (callers check that first).
inline const char* check_compact_sampler(const CompactSamplerView& v) {
    if (v.slices < 2 || v.slices > 1024 || v.rows < 1 || v.rows > 4096 || v.cols < 1 || v.cols > 4096)
        return "slices, rows or cols out of range (2-1024, 1-4096, 1-4096)";
    if (!(v.cos_theta_max >= 0.0 && v.cos_theta_max < 1.0)) return "cos_theta_max must be in [0, 1)";
    if (!(v.cosine_share > 0.0 && v.cosine_share < 1.0)) return "cosine_share must be in (0, 1)";
    if (v.s_edges[0] != 0.0f || v.s_edges[v.rows] != 0.5f) return "row edges must run from 0 to 0.5";
    for (int r = 0; r < v.rows; ++r)
        if (!(v.s_edges[r] < v.s_edges[r + 1])) return "row edges must increase";
    const std::size_t rows = static_cast<std::size_t>(v.slices) * v.rows;
    for (std::size_t row = 0; row < rows; ++row) {
        const std::uint16_t* c = v.col_cdf + row * v.cols;
        for (int i = 1; i < v.cols; ++i)
            if (c[i] < c[i - 1]) return "a CDF decreases";
        if (c[v.cols - 1] != kColUnits) return "a CDF does not end at full scale";
    }
    for (int k = 0; k < v.slices; ++k) {
        const std::uint32_t* c = v.row_cdf + static_cast<std::size_t>(k) * v.rows;
        for (int i = 1; i < v.rows; ++i)
            if (c[i] < c[i - 1]) return "a CDF decreases";
        if (c[v.rows - 1] != kRowUnits) return "a CDF does not end at full scale";
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(v.slices) * (v.rows + 1); ++i) {
        const std::uint16_t h = v.edge_weight[i];
        if ((h & 0x8000u) || (h & 0x7c00u) == 0x7c00u) return "an edge weight is negative or not finite";
    }
    return nullptr;
}

}  // namespace brdfz::runtime::kernels
