// Continuous Rusinkiewicz bin coordinates of direction pairs and the interpolation spans around them,
// shared by the representations that look values up on a GridSpec's axes (tabular, factored).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/table.h"

namespace brdfz::detail {

// Continuous bin coordinates (θh, θd, φd) of a direction pair on a grid.
struct BinCoords {
    double uh, ud, up;
};

// MERL's arithmetic (see table.h): what nearest lookup must match bit for bit.
inline BinCoords bin_coords(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 h = half_vector(wi, wo);
    const Vec3 d = difference_vector(wi, half_frame(h));
    return {axis::theta_h_to_u(elevation(h), g.n_theta_h), axis::theta_d_to_u(elevation(d), g.n_theta_d),
            axis::phi_d_to_u(std::atan2(d.y, d.x), g.n_phi_d)};
}

// atan(t) for t in [0, 1] as t·P(t²), a least-squares fit of the relative error: |rel err| < 6e-11.
// Estrin's scheme: a dependency chain of 4 multiply-adds instead of Horner's 11.
inline double atan01(double t) {
    constexpr double c[] = {0.99999999994136979,   -0.33333331572392677, 0.19999912082711904,
                            -0.1428398114194897,   0.1109324385371387,   -0.089802498131937941,
                            0.072457466235865964,  -0.054279596397618646, 0.034210157407729216,
                            -0.016112066961960693, 0.0048510884142120014, -0.00068481937721016906};
    const double x = t * t, x2 = x * x, x4 = x2 * x2, x8 = x4 * x4;
    const double p01 = c[0] + c[1] * x, p23 = c[2] + c[3] * x, p45 = c[4] + c[5] * x, p67 = c[6] + c[7] * x;
    const double p89 = c[8] + c[9] * x, pab = c[10] + c[11] * x;
    const double q0 = p01 + p23 * x2, q1 = p45 + p67 * x2, q2 = p89 + pab * x2;
    return t * ((q0 + q1 * x4) + q2 * x8);
}

// The angle of (x, y) folded into [0, π] (φ ~ φ + π, as MERL folds φd by reciprocity), to ~1e-10
// relative. No libm call and no branch: octant tests on random directions would mispredict half the
// time, and branch-free code vectorises. NaN in, NaN out.
inline double fast_half_turn_angle(double y, double x) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    const double a = atan01(std::min(ax, ay) / std::max(ax, ay));
    const double steep = ay > ax ? 1.0 : 0.0, left = (x < 0.0) != (y < 0.0) ? 1.0 : 0.0;
    const double b = a + steep * (std::numbers::pi / 2 - 2.0 * a);  // π/2 - a when |y| > |x|
    return b + left * (std::numbers::pi - 2.0 * b);                  // π - b in the 2nd quadrant
}

// bin_coords without asin, atan2 or a normalisation: every angle is an arctangent of two lengths
// in one (arbitrary) scale, from s = wi + wo, the unnormalised half vector:
//   θh = atan(|s_xy| / s_z),  θd = atan(|wi × s| / wi·s),
//   φd = atan(d_y / d_x) with d_x, d_y (half_frame's) both multiplied by |s|·|s_xy| > 0.
// Within 5e-8 bins of bin_coords (angles to 2.2e-10 relative; rounding ~1e-16 / sinθd in φd), except
// where φd is ill-conditioned (θh or θd below 1e-6): there up is kIllConditioned, beyond any grid, for
// the callers to fall back to bin_coords. Branch-free, so the compiler vectorises it across pairs.
constexpr double kIllConditioned = 1e300;
inline BinCoords fast_bin_coords(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 s = wi + wo;
    const double rxy2 = s.x * s.x + s.y * s.y;
    const double rxy = std::sqrt(rxy2);
    const double len = std::sqrt(rxy2 + s.z * s.z);
    const Vec3 cr{wi.y * s.z - wi.z * s.y, wi.z * s.x - wi.x * s.z, wi.x * s.y - wi.y * s.x};
    const double sin_d = std::sqrt(dot(cr, cr));  // sinθd·|s|
    const double theta_h = fast_half_turn_angle(rxy, s.z);
    const double theta_d = fast_half_turn_angle(sin_d, dot(wi, s));
    const double phi_d = fast_half_turn_angle(-cr.z * len, s.z * (wi.x * s.x + wi.y * s.y) - wi.z * rxy2);
    constexpr double kMinSin = 1e-6;
    const bool sure = (rxy > kMinSin * len) & (sin_d > kMinSin * len);
    const double up = phi_d * (1.0 / std::numbers::pi) * g.n_phi_d;
    return {std::sqrt(theta_h * (2.0 / std::numbers::pi)) * g.n_theta_h,
            theta_d * (2.0 / std::numbers::pi) * g.n_theta_d, std::max(up, sure ? 0.0 : kIllConditioned)};
}

// Clamp to [0, hi] with comparisons, NaN to 0: std::fmin/fmax are out-of-line libm calls here.
inline double clamp0(double u, double hi) { return u > 0.0 ? (u < hi ? u : hi) : 0.0; }

// Two neighbouring samples along a clamped axis and the weight of the second.
struct Span {
    int i0, i1;
    double t;
};

inline Span clamped_span(double c, int n) {
    c = clamp0(c, n - 1.0);
    const int i0 = static_cast<int>(c);
    const int i1 = i0 + 1 < n ? i0 + 1 : i0;
    return {i0, i1, c - i0};
}

// c is in [-0.5, n] (φd folded to [0, π], minus the sample offset) or NaN: one wrap, not fmod.
inline Span periodic_span(double c, int n) {
    if (c < 0.0) c += n;
    if (!(c < n)) c = 0.0;  // c == n after rounding, or NaN
    const int i0 = static_cast<int>(c);
    return {i0, i0 + 1 < n ? i0 + 1 : 0, c - i0};
}

struct Corners {
    Span h, d, p;
};

// Linear lookup uses the fast coordinates (5e-8 bins off: ~1e-9 relative in the result) except where
// they flagged φd as ill-conditioned.
inline Corners linear_corners(const GridSpec& g, BinCoords c, const Vec3& wi, const Vec3& wo) {
    if (!(c.up <= g.n_phi_d)) [[unlikely]]  // kIllConditioned or NaN
        c = bin_coords(g, wi, wo);
    const double off = g.sample_offset();
    return {clamped_span(c.uh - off, g.n_theta_h), clamped_span(c.ud - off, g.n_theta_d),
            periodic_span(c.up - off, g.n_phi_d)};
}
}  // namespace brdfz::detail
