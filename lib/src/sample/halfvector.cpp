// The half-vector sampler. Its block kernel (draw_lanes) is compiled for each of Highway's targets
// (hwy/foreach_target.h includes this file again for each; lib/runtime/src/hwy_dispatch.h picks one
// at run time), the rest once.
#ifndef BRDFZ_SAMPLE_HALFVECTOR_ONCE
#define BRDFZ_SAMPLE_HALFVECTOR_ONCE
#include "brdfz/sample/halfvector.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/azimuth.h"
#include "detail/fast_math.h"
#include "detail/grid_sweep.h"
#include "detail/simd.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;

using detail::Azimuth;
using detail::reflect;

// Half vector at cell coordinates (x, y), with φh = ±π x relative to wo.
Vec3 half_at(double x, double y, double sign) {
    return spherical_direction(kPi / 2.0 * y * y, sign * kPi * x);
}

// wo's elevation without asin, to ~1e-10: it only places wo between two slices, and sample() and
// pdf() place it alike. sin_o = ‖wo_xy‖, which draw() also needs for wo's azimuth.
double view_elevation(double sin_o, const Vec3& wo) { return detail::fast_half_turn_angle(sin_o, wo.z); }

constexpr double kBelowOne = 0x1.fffffffffffffp-1;  // the largest double below 1

// The two slices around wo's elevation: the lower one and the weight of the upper. Comparisons, not
// std::fmin/fmax (out-of-line libm calls); NaN goes to slice 0.
struct SliceSpan {
    int k0;
    double t;
};
[[gnu::always_inline]] inline SliceSpan slice_span(double theta_o, double theta_max, int K) {
    const double scaled = theta_o / theta_max * (K - 1);
    const double pos = scaled > 0.0 ? (scaled < K - 1.0 ? scaled : K - 1.0) : 0.0;
    const int k0 = std::min(static_cast<int>(pos), K - 2);
    return {k0, pos - k0};
}

// What a data draw needs before its cell search, and what it needs after: draw() and the block kernel
// run these same functions, one draw at a time or across a block, so their results agree bit for bit.
struct SamplerView {
    double share, theta_max;
    int K;
};

// The slices' tables end to end (HalfVectorSampler::stacked_), each slice rows × cols cells, as a
// view of slice 0: the block kernel indexes the stack from there across draws.
using StackView = Piecewise2D::View;

struct Placement {
    double sin_o, v1, v2, sign;  // v1, v2: the slice's u, v1 below 1
    int slice;
};

[[gnu::always_inline]] inline Placement place(const SamplerView& v, const Vec3& wo, double u1, double u2) {
    double v1 = (u1 - v.share) / (1.0 - v.share);
    const double sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    const SliceSpan sp = slice_span(view_elevation(sin_o, wo), v.theta_max, v.K);
    const bool upper = !(v1 < 1.0 - sp.t);
    v1 = upper ? (v1 - (1.0 - sp.t)) / sp.t : v1 / (1.0 - sp.t);
    // One bit of u2 picks the side of wo's plane; the rest drives the column.
    const double sign = u2 < 0.5 ? 1.0 : -1.0;
    const double v2 = u2 < 0.5 ? 2.0 * u2 : 2.0 * u2 - 1.0;
    return {sin_o, v1 < kBelowOne ? v1 : kBelowOne, v2, sign, upper ? sp.k0 + 1 : sp.k0};
}

// The data share's density of wi per unit solid angle, 0 where it has none: pdf()'s, and a cosine
// draw's. The half vector's angles in wo's frame come from s = wi + wo, unnormalised, through the
// polynomial arctangent: no libm call, so the block kernel runs it inline and agrees with pdf() to
// the bit. Every index stays within the tables whatever wi is (NaN included).
[[gnu::always_inline]] inline double data_density(const SamplerView& v, const StackView& st, const Vec3& wo,
                                                  double sin_o, const Vec3& wi) {
    const Vec3 s = Azimuth(wo, sin_o).to_local(wi + wo);
    const double rxy = std::sqrt(s.x * s.x + s.y * s.y), len = std::sqrt(rxy * rxy + s.z * s.z);
    const double y = std::sqrt(detail::fast_half_turn_angle(rxy, s.z) / (kPi / 2.0));
    const double x = detail::fast_half_turn_angle(std::fabs(s.y), s.x) / kPi;  // |φh − φo| / π; NaN at the pole
    const bool inside = y < 1.0;
    const double yc = inside ? y : 0.0, xc = x < kBelowOne ? x : kBelowOne;
    // Piecewise2D::View::pdf's cell of (xc, yc), in the two slices around wo's elevation.
    const int R = st.rows, C = st.cols;
    const int r = std::min(static_cast<int>(yc * R), R - 1), c = std::min(static_cast<int>(xc * C), C - 1);
    const SliceSpan sp = slice_span(view_elevation(sin_o, wo), v.theta_max, v.K);
    const float* d = st.density + r * C + c;
    const double p_xy = (1.0 - sp.t) * d[sp.k0 * R * C] + sp.t * d[(sp.k0 + 1) * R * C];
    // dωi/dx dy: 4 (wo·h) · 2π² y sinθh, with h = s / |s| and sinθh = |s_xy| / |s|.
    const double jac = 4.0 * ((sin_o * s.x + wo.z * s.z) / len) * 2.0 * kPi * kPi * y * (rxy / len);
    const double p = p_xy / jac;
    return (inside & (std::fabs(p) < std::numeric_limits<double>::infinity()) & (p > 0.0)) ? p : 0.0;
}

struct Finish {
    Vec3 wi;
    double pdf, sin_h, cos_h, sin_p, cos_p;
    bool ok;  // wi above the horizon, with a finite positive density
};

// From the drawn cell point (x, y): h, wi, and the pdf as pdf(wo, wi) gives it, from wi itself: the
// cell density of the draw could differ from it where rounding puts wi across a cell edge.
[[gnu::always_inline]] inline Finish finish(const SamplerView& v, const StackView& st, const detail::SinCosTable& table,
                                            const Vec3& wo, const Placement& pl, double x, double y) {
    // half_at(x, y, sign), with table-based sines and cosines.
    const detail::SinCosTable::SinCos th = table(kPi / 2.0 * y * y), ph = table(kPi * x);
    const double sin_p = pl.sign * ph.s;
    const Vec3 h = Azimuth(wo, pl.sin_o).to_world({th.s * ph.c, th.s * sin_p, th.c});
    const double cos_d = dot(wo, h);
    const Vec3 wi = (2.0 * cos_d) * h - wo;  // reflect(wo, h)
    const double data = data_density(v, st, wo, pl.sin_o, wi);
    const bool ok = (wi.z > 0.0) & (data > 0.0);
    return {wi, v.share * wi.z / kPi + (1.0 - v.share) * data, th.s, th.c, sin_p, ph.c, ok};
}

// A cosine-weighted draw with sample()'s full pdf at it, from u1 in [0, share) and u2 in [0, 1).
// φ = 2πu2 through the half-turn sine table: φ and 2π − φ share a cosine, their sines differ in sign.
struct CosineDraw {
    Vec3 wi;
    double pdf;
    bool ok;  // wi above the horizon
};
[[gnu::always_inline]] inline CosineDraw cosine_draw(const SamplerView& v, const StackView& st,
                                                     const detail::SinCosTable& table, const Vec3& wo, double u1,
                                                     double u2) {
    const double e = u1 / v.share, r = std::sqrt(e);
    const bool lower = u2 < 0.5;
    const detail::SinCosTable::SinCos phi = table(2.0 * kPi * (lower ? u2 : 1.0 - u2));
    const Vec3 wi{r * phi.c, r * (lower ? phi.s : -phi.s), std::sqrt(1.0 - e)};
    const double sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    return {wi, v.share * wi.z / kPi + (1.0 - v.share) * data_density(v, st, wo, sin_o, wi), wi.z > 0.0};
}

// Piecewise2D::sample's CDF search (find_interval) from the guide entry, in a fixed two steps of its
// scan (it takes about one on average), on `cdf` from index `base`: the interval, and in `found`
// whether it is find_interval's. It is when the scan has ended: then cdf[i] <= u < cdf[i + 1], so the
// interval is not empty either. Every index stays within the tables for any u, NaN or inf. Indices are
// ints (the stacked tables' sizes are checked), which the gathers need. In two parts, the guide entry
// (where the scan starts) and the scan, so that the block kernel can run them as separate passes.
[[gnu::always_inline]] inline int guide_entry(const std::uint32_t* guide, int guide_base, int n, double u) {
    const float x = static_cast<float>(u);
    // x is at most 1 for a data draw; the bound keeps the bucket of other lanes (u2 = inf) in range.
    const int j = std::min(static_cast<int>(x > 0.0f ? std::min(static_cast<double>(x), 1.0) * n : 0.0), n - 1);
    return static_cast<int>(guide[guide_base + j]);
}
[[gnu::always_inline]] inline int scan_interval(const float* cdf, int base, int n, int i, double u, bool& found) {
    const float x = static_cast<float>(u);
    for (int step = 0; step < 2; ++step) i += (i < n - 1) & (cdf[base + i + 1] <= x);
    found = cdf[base + i + 1] > x;
    return i;
}

// Piecewise2D's cell_coord, (i + f) / n, and whether it needs no nudge to lie in cell i.
[[gnu::always_inline]] inline double cell_coord(int i, int n, double f, bool& found) {
    const double v = (i + f) / n;
    found = !(v * n >= i + 1.0) & !(v * n < i);
    return v;
}

// Piecewise2D::sample(u1, u2) on a slice's stacked tables: the same operations (float differences of
// CDF entries included), so when `found` the same point. In three steps, each a pass across the block
// kernel's draws: the row; the guide entry of the column's search; the column and the cell point. One pass for all three ran each draw's chain of
// dependent table reads in turn, with few of the next draws' reads overlapping it.
struct Row {
    int r;      // the row within the slice
    double fy;  // where u1 lies within it
    bool found;
};
[[gnu::always_inline]] inline Row find_row(const StackView& v, int slice, double u1) {
    const int R = v.rows, mb = slice * (R + 1);
    bool found;
    const int r = scan_interval(v.marginal, mb, R, guide_entry(v.marginal_guide, slice * R, R, u1), u1, found);
    const float w_r = v.marginal[mb + r + 1] - v.marginal[mb + r];
    return {r, std::clamp((u1 - v.marginal[mb + r]) / w_r, 0.0, 1.0), found};
}
[[gnu::always_inline]] inline int column_start(const StackView& v, int slice, int r, double u2) {
    return guide_entry(v.conditional_guide, (slice * v.rows + r) * v.cols, v.cols, u2);
}
struct Cell {
    double x, y;
    bool found;
};
[[gnu::always_inline]] inline Cell find_column(const StackView& v, int slice, const Row& row, int start, double u2) {
    const int R = v.rows, C = v.cols, rs = slice * R + row.r, cb = rs * (C + 1);
    bool found_c, found_x, found_y;
    const int c = scan_interval(v.conditional, cb, C, start, u2, found_c);
    const float w_c = v.conditional[cb + c + 1] - v.conditional[cb + c];
    const double fx = std::clamp((u2 - v.conditional[cb + c]) / w_c, 0.0, 1.0);
    const double x = cell_coord(c, C, fx, found_x), y = cell_coord(row.r, R, row.fy, found_y);
    return {x, y, static_cast<bool>(row.found & found_c & found_x & found_y)};
}
[[gnu::always_inline]] inline Cell find_cell(const StackView& v, int slice, double u1, double u2) {
    const Row row = find_row(v, slice, u1);
    return find_column(v, slice, row, column_start(v, slice, row.r, u2), u2);
}

// Piecewise2D itself, for the draws whose find_cell did not settle (its scans are longer, or its cell
// coordinates need a nudge).
Cell exact_cell(const StackView& v, int slice, double u1, double u2) {
    const Piecewise2D::Point p = v.stacked(slice).sample(u1, u2);
    return {p.x, p.y, true};
}

// HalfVectorSampler::draw_block's data draws in passes over the block, each across draws: (1) placement;
// (2) the cell searches (gathers from the stacked tables); (3) the half vector, wi and the pdf; then
// the cosine draws.
[[gnu::always_inline]] inline void draw_lanes(const SamplerView& v, const StackView& st,
                                              const detail::SinCosTable& table, const Vec3* wo,
                                              const std::array<double, 2>* u, std::size_t n,
                                              HalfVectorSampler::Draws& out) {
    constexpr std::size_t B = HalfVectorSampler::kBlock;
    // Arrays of numbers, not of structs, or the loops do not vectorise; flags as 64-bit integers,
    // the doubles' width (a select on bytes between doubles does not vectorise).
    double sin_o[B], v1[B], v2[B], sign[B], x[B], y[B];
    int slice[B];
    std::int64_t data[B], cosine[B];
    for (std::size_t k = 0; k < n; ++k) {
        const double u1 = u[k][0], u2 = u[k][1];
        // Brdf::can_draw, split into data and cosine draws.
        const bool can = (wo[k].z > 0.0) & (u1 >= 0.0) & (u1 < 1.0) & (u2 >= 0.0) & (u2 < 1.0);
        data[k] = can & (u1 >= v.share);
        cosine[k] = can & (u1 < v.share);
        const Placement pl = place(v, wo[k], u1, u2);
        sin_o[k] = pl.sin_o, v1[k] = pl.v1, v2[k] = pl.v2, sign[k] = pl.sign, slice[k] = pl.slice;
    }
    // find_cell's steps, each a pass.
    int row[B], start[B];
    double fy[B];
    std::int64_t row_found[B], redo[B];
    for (std::size_t k = 0; k < n; ++k) {
        const Row r = find_row(st, slice[k], v1[k]);
        row[k] = r.r, fy[k] = r.fy, row_found[k] = r.found;
    }
    for (std::size_t k = 0; k < n; ++k) start[k] = column_start(st, slice[k], row[k], v2[k]);
    for (std::size_t k = 0; k < n; ++k) {
        const Cell c = find_column(st, slice[k], {row[k], fy[k], row_found[k] != 0}, start[k], v2[k]);
        x[k] = c.x, y[k] = c.y;
        redo[k] = data[k] & !c.found;
    }
    for (std::size_t k = 0; k < n; ++k) {
        if (!redo[k]) continue;
        const Cell c = exact_cell(st, slice[k], v1[k], v2[k]);
        x[k] = c.x, y[k] = c.y;
    }
    // The results into local arrays first: the compiler cannot rule out that `out` overlaps the sine
    // table it gathers from, and then does not vectorise.
    double wx[B], wy[B], wz[B], pdf[B], sh[B], ch[B], sp[B], cp[B], co[B];
    std::int64_t ok[B];
    for (std::size_t k = 0; k < n; ++k) {
        const Placement pl{sin_o[k], v1[k], v2[k], sign[k], slice[k]};
        const Finish f = finish(v, st, table, wo[k], pl, x[k], y[k]);
        ok[k] = data[k] & f.ok;
        wx[k] = f.wi.x, wy[k] = f.wi.y, wz[k] = f.wi.z, pdf[k] = f.pdf;
        sh[k] = f.sin_h, ch[k] = f.cos_h, sp[k] = f.sin_p, cp[k] = f.cos_p, co[k] = wo[k].z;
    }
    for (std::size_t k = 0; k < n; ++k) {
        const bool o = ok[k] != 0;
        out.wi_x[k] = o ? wx[k] : 0.0, out.wi_y[k] = o ? wy[k] : 0.0, out.wi_z[k] = o ? wz[k] : 0.0;
        out.pdf[k] = o ? pdf[k] : 0.0;
        out.half[k] = o;
        out.sin_h[k] = o ? sh[k] : 0.0, out.cos_h[k] = o ? ch[k] : 0.0;
        out.sin_p[k] = o ? sp[k] : 0.0, out.cos_p[k] = o ? cp[k] : 0.0;
        out.sin_o[k] = o ? sin_o[k] : 0.0, out.cos_o[k] = o ? co[k] : 0.0;
    }
    // The cosine share's draws, a twentieth of them, one at a time: across the block they would cost
    // every lane the density lookup.
    for (std::size_t k = 0; k < n; ++k) {
        if (!cosine[k]) continue;
        const CosineDraw c = cosine_draw(v, st, table, wo[k], u[k][0], u[k][1]);
        out.wi_x[k] = c.ok ? c.wi.x : 0.0, out.wi_y[k] = c.ok ? c.wi.y : 0.0, out.wi_z[k] = c.ok ? c.wi.z : 0.0;
        out.pdf[k] = c.ok ? c.pdf : 0.0;
    }
}

}  // namespace
}  // namespace brdfz
#endif  // BRDFZ_SAMPLE_HALFVECTOR_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sample/halfvector.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace brdfz::HWY_NAMESPACE {

// draw_lanes for the target, whole (flatten: its loops vectorise only where nothing in them is a call).
// Without FMA contraction (brdfz_float), so every target gives draw()'s bits.
[[gnu::flatten]] void DrawLanes(const SamplerView& v, const StackView& st, const detail::SinCosTable& table,
                                const Vec3* wo, const std::array<double, 2>* u, std::size_t n,
                                HalfVectorSampler::Draws& out) {
    draw_lanes(v, st, table, wo, u, n, out);
}

}  // namespace brdfz::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "hwy_dispatch.h"

namespace brdfz {

HalfVectorSampler::HalfVectorSampler(const Brdf& brdf, const HalfVectorSamplerOptions& o) : options_(o) {
    // draw_block indexes the slices' stacked tables with ints.
    if (o.n_theta_o < 2 || o.n_theta_h < 1 || o.n_phi < 1 || o.n_theta_o > 1024 || o.n_theta_h > 4096 ||
        o.n_phi > 4096 || static_cast<double>(o.n_theta_o) * o.n_theta_h * (o.n_phi + 1) >= 0x1p31)
        throw ValueError("half-vector sampler: resolutions out of range");
    if (!(o.cosine_share > 0.0 && o.cosine_share < 1.0))
        throw ValueError("half-vector sampler: cosine_share must be in (0, 1)");
    const int K = o.n_theta_o, R = o.n_theta_h, C = o.n_phi;
    theta_o_.resize(K);
    for (int k = 0; k < K; ++k) theta_o_[k] = kMaxThetaODeg * kPi / 180.0 * k / (K - 1);
    std::vector<Piecewise2D> slices(K);

    // Each slice: the integrand f·cosθi·(dωi/dx dy) averaged over 2×2 points per cell.
    detail::parallel_for(K, o.threads, [&](int, int k) {
        const Vec3 wo = spherical_direction(theta_o_[k], 0.0);
        const std::size_t cells = static_cast<std::size_t>(R) * C;
        std::vector<Vec3> wi(4 * cells), wos(4 * cells, wo);
        std::vector<double> jac(4 * cells);
        for (int r = 0; r < R; ++r)
            for (int c = 0; c < C; ++c)
                for (int s = 0; s < 4; ++s) {
                    const double y = (r + 0.25 + 0.5 * (s >> 1)) / R, x = (c + 0.25 + 0.5 * (s & 1)) / C;
                    const Vec3 h = half_at(x, y, 1.0);
                    const std::size_t i = 4 * (static_cast<std::size_t>(r) * C + c) + s;
                    wi[i] = reflect(wo, h);
                    jac[i] = 4.0 * std::fmax(dot(wo, h), 0.0) * 2.0 * kPi * kPi * y * std::sin(kPi / 2.0 * y * y);
                }
        std::vector<Rgb> f(wi.size());
        brdf.eval(wi, wos, f);
        std::vector<float> weights(cells);
        for (std::size_t cell = 0; cell < cells; ++cell) {
            double sum = 0.0;
            for (int s = 0; s < 4; ++s) {
                const std::size_t i = 4 * cell + s;
                const double mean = (f[i][0] + f[i][1] + f[i][2]) / 3.0;
                // Non-finite or negative data gets no importance; the cosine share still covers it.
                if (std::isfinite(mean) && mean > 0.0 && wi[i].z > 0.0) sum += mean * wi[i].z * jac[i];
            }
            // Values near the float limit (a table may hold up to FLT_MAX) saturate rather than overflow.
            weights[cell] = std::isfinite(sum) ? static_cast<float>(std::fmin(sum, FLT_MAX)) : 0.0f;
        }
        slices[k] = Piecewise2D(weights, R, C);
    });
    const auto append = [](auto& to, auto from) { to.insert(to.end(), from.begin(), from.end()); };
    for (const Piecewise2D& s : slices) {
        append(stacked_.marginal, s.marginal_cdf());
        append(stacked_.conditional, s.conditional_cdf());
        append(stacked_.density, s.densities());
        append(stacked_.marginal_guide, s.marginal_guide());
        append(stacked_.conditional_guide, s.conditional_guide());
    }
    first_ = {R,
              C,
              stacked_.marginal.data(),
              stacked_.conditional.data(),
              stacked_.density.data(),
              stacked_.marginal_guide.data(),
              stacked_.conditional_guide.data()};
}

std::size_t HalfVectorSampler::nbytes() const {
    const Stacked& s = stacked_;
    return theta_o_.size() * sizeof(double) +
           (s.marginal.size() + s.conditional.size() + s.density.size()) * sizeof(float) +
           (s.marginal_guide.size() + s.conditional_guide.size()) * sizeof(std::uint32_t);
}

double HalfVectorSampler::pdf(const Vec3& wo, const Vec3& wi) const {
    const SamplerView v{options_.cosine_share, theta_o_.back(), static_cast<int>(theta_o_.size())};
    const double sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    return v.share * wi.z / kPi + (1.0 - v.share) * data_density(v, first_, wo, sin_o, wi);
}

HalfVectorSampler::Draw HalfVectorSampler::draw(const Vec3& wo, double u1, double u2) const {
    // Each path builds its result whole: a Draw zeroed up front cost a `rep stos` per draw.
    const SamplerView v{options_.cosine_share, theta_o_.back(), static_cast<int>(theta_o_.size())};
    if (u1 < v.share) {
        const CosineDraw c = cosine_draw(v, first_, detail::half_turn_sincos(), wo, u1, u2);
        return c.ok ? Draw{{c.wi, c.pdf, {}}} : Draw{};
    }
    const Placement pl = place(v, wo, u1, u2);
    // The block kernel's cell search, and its fallback where that does not settle.
    Cell c = find_cell(first_, pl.slice, pl.v1, pl.v2);
    if (!c.found) c = exact_cell(first_, pl.slice, pl.v1, pl.v2);
    const Finish f = finish(v, first_, detail::half_turn_sincos(), wo, pl, c.x, c.y);
    if (!f.ok) return {};
    return {{f.wi, f.pdf, {}}, true, f.sin_h, f.cos_h, f.sin_p, f.cos_p, pl.sin_o, wo.z};
}

void HalfVectorSampler::draw_block(const Vec3* wo, const std::array<double, 2>* u, std::size_t n, Draws& out) const {
    const SamplerView v{options_.cosine_share, theta_o_.back(), static_cast<int>(theta_o_.size())};
    static const auto builds = BRDFZ_HWY_BUILDS(DrawLanes);
    builds.at(detail::simd_level())(v, first_, detail::half_turn_sincos(), wo, u, n, out);
}

}  // namespace brdfz
#endif  // HWY_ONCE
