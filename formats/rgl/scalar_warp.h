// The RGL warps' arithmetic one point at a time, in double over the float tables: the anisotropic path
// (aniso.cpp) and the isotropic kernels' scalar reference (reference.cpp) share it. The warps are
// Mitsuba 3's Marginal2D (marginal2d.h); the batch kernels (kernels.cpp) are the same arithmetic in
// vectors. A Table is anything indexable by entry giving a double: one slice's table, or slices blended.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "brdfz/frame.h"

namespace brdfz::rgl::detail {

struct WarpPoint {
    double x = 0, y = 0, pdf = 0;
};

namespace scalar {

constexpr double kPi = std::numbers::pi;

// The parameterisation's unit coordinates: a square-root axis in elevation, linear in azimuth.
inline double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / kPi)); }
inline double u_of_phi(double phi) { return (phi + kPi) * (0.5 / kPi); }
inline double clamp01(double v) { return std::fmin(std::fmax(v, 0.0), 1.0); }  // NaN goes to 0
inline double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }
inline bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Where x falls among increasing values (Mitsuba's interval search, clamped): the lower index, the step
// to the upper one (0 for a single value) and the upper one's weight.
struct SliceAxis {
    std::size_t lower = 0, step = 0;
    double w = 0.0;
};
inline SliceAxis slice_axis(const std::vector<float>& v, double x) {
    if (v.size() < 2) return {};
    const auto it = std::lower_bound(v.begin() + 1, v.end() - 1, x, [](float a, double b) { return a < b; });
    const auto lower = static_cast<std::size_t>(it - v.begin()) - 1;
    return {lower, 1, clamp01((x - v[lower]) / (static_cast<double>(v[lower + 1]) - v[lower]))};
}

// The grid cell (patch) of a rows × cols table over [0, 1]² holding a point, and the point's position
// in it; points outside are clamped onto the square.
struct Patch {
    std::size_t ix, iy;
    double fx, fy;
};
inline Patch locate(double x, double y, std::size_t rows, std::size_t cols) {
    const double sx = clamp01(x) * static_cast<double>(cols - 1), sy = clamp01(y) * static_cast<double>(rows - 1);
    const std::size_t ix = std::min(static_cast<std::size_t>(sx), cols - 2);
    const std::size_t iy = std::min(static_cast<std::size_t>(sy), rows - 2);
    return {ix, iy, sx - static_cast<double>(ix), sy - static_cast<double>(iy)};
}
template <typename Table>
double bilinear(const Table& t, std::size_t rows, std::size_t cols, double x, double y) {
    const Patch q = locate(x, y, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    return lerp(lerp(t[i], t[i + 1], q.fx), lerp(t[i + cols], t[i + cols + 1], q.fx), q.fy);
}

// The integral over the first fraction t of a segment of length `width` along which a function goes
// linearly from v0 to v1, and its inverse on a unit-width segment (rationalised: no cancellation, no
// special case).
inline double partial_integral(double t, double width, double v0, double v1) { return t * lerp(v0, v1, 0.5 * t) * width; }
inline double invert_partial_integral(double s, double v0, double v1) {
    const double denom = v0 + std::sqrt(std::fmax(v0 * v0 + 2.0 * s * (v1 - v0), 0.0));
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;
}
// The largest j in [0, n) with cdf(j) < u, or 0 (cdf non-decreasing, cdf(0) = 0).
template <typename Cdf>
std::size_t find_cell(std::size_t n, const Cdf& cdf, double u) {
    std::size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const std::size_t mid = (lo + hi + 1) / 2;
        if (cdf(mid) < u) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

// dω/du_m for the direction reflected about m; 0 for back-facing m.
inline double solid_angle_per_unit_square(double u_theta, double theta_m, double w_dot_m) {
    return std::fmax(2.0 * kPi * kPi * u_theta * std::sin(theta_m) * 4.0 * w_dot_m, 0.0);
}

// A warp's sample and its inverse (marginal2d.h: the density `data`, rows × cols; the conditional CDFs
// `cond`, rows × (cols − 1); the marginal CDF `marg`, rows − 1). sample maps u uniform on [0, 1]² to a
// point of the square with the density there; invert maps a point back.
template <typename Table>
WarpPoint warp_sample(const Table& data, const Table& cond, const Table& marg, std::size_t rows, std::size_t cols,
                      double ux, double uy) {
    const std::size_t n_cond = cols - 1;
    const double width = 1.0 / static_cast<double>(cols - 1), height = 1.0 / static_cast<double>(rows - 1);
    ux = clamp01(ux);
    uy = clamp01(uy);
    const auto marg_at = [&](std::size_t j) { return j == 0 ? 0.0 : marg[j - 1]; };
    const std::size_t iy = find_cell(rows - 1, marg_at, uy);
    const std::size_t row0 = iy * n_cond, row1 = row0 + n_cond;
    const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
    const double fy = invert_partial_integral((uy - marg_at(iy)) / height, r0, r1);
    const double target = ux * lerp(r0, r1, fy);
    const auto cond_at = [&](std::size_t j) { return j == 0 ? 0.0 : lerp(cond[row0 + j - 1], cond[row1 + j - 1], fy); };
    const std::size_t ix = find_cell(cols - 1, cond_at, target);
    const std::size_t i = iy * cols + ix;
    const double c0 = lerp(data[i], data[i + cols], fy), c1 = lerp(data[i + 1], data[i + cols + 1], fy);
    const double fx = invert_partial_integral((target - cond_at(ix)) / width, c0, c1);
    return {(static_cast<double>(ix) + fx) * width, (static_cast<double>(iy) + fy) * height, lerp(c0, c1, fx)};
}
template <typename Table>
WarpPoint warp_invert(const Table& data, const Table& cond, const Table& marg, std::size_t rows, std::size_t cols,
                      double px, double py) {
    const std::size_t n_cond = cols - 1;
    const Patch q = locate(px, py, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    const double c0 = lerp(data[i], data[i + cols], q.fy), c1 = lerp(data[i + 1], data[i + cols + 1], q.fy);
    const std::size_t row0 = q.iy * n_cond, row1 = row0 + n_cond;
    double x = partial_integral(q.fx, 1.0 / static_cast<double>(cols - 1), c0, c1);
    if (q.ix > 0) x += lerp(cond[row0 + q.ix - 1], cond[row1 + q.ix - 1], q.fy);
    const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
    x /= lerp(r0, r1, q.fy);
    double y = partial_integral(q.fy, 1.0 / static_cast<double>(rows - 1), r0, r1);
    if (q.iy > 0) y += marg[q.iy - 1];
    return {x, y, lerp(c0, c1, q.fx)};
}

}  // namespace scalar
}  // namespace brdfz::rgl::detail
