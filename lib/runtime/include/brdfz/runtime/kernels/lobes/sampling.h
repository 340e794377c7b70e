// What the lobe families' samplers share (their `sample` and `pdf`, lobe.h): reflection about a half
// vector, half vectors folded toward wo, cosine-weighted directions, a bracketed Newton inversion of a
// CDF. The helpers are always inlined and take sin/cos by polynomial, so that the mixture's loops over
// lanes (the core's LobeMixture::sample_block) vectorise where a family's code allows: a call stops
// the vectoriser.
#pragma once

#include <cmath>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::lobes::sampling {

[[gnu::always_inline]] inline Vec3 reflect(const Vec3& wo, const Vec3& h) { return (2.0 * dot(wo, h)) * h - wo; }

// Unit half vector of wo and w, or false where it is undefined (w = −wo).
[[gnu::always_inline]] inline bool half_of(const Vec3& wo, const Vec3& w, Vec3& h) {
    const Vec3 s = wo + w;
    const double n2 = dot(s, s);
    if (!(n2 > 1e-30)) return false;
    h = (1.0 / std::sqrt(n2)) * s;
    return true;
}

// Orthonormal basis around a unit vector (Duff et al., JCGT 2017): no branch on the pole.
struct Basis {
    Vec3 t, b, n;
    explicit Basis(const Vec3& n_) : n(n_) {
        const double sign = std::copysign(1.0, n.z);
        const double a = -1.0 / (sign + n.z), c = n.x * n.y * a;
        t = {1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
        b = {c, sign + n.y * n.y * a, -n.y};
    }
    Vec3 to_world(const Vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

// sin and cos of 2πu for u in [0, 1), from the half-turn polynomial (a few ulp of libm's).
[[gnu::always_inline]] inline runtime::kernels::SinCos turn(double u) {
    const bool first = u < 0.5;
    const runtime::kernels::SinCos r = runtime::kernels::sincos_half_turn(2.0 * kPi * (first ? u : 1.0 - u));
    return {first ? r.s : -r.s, r.c};
}

// max(x, 0) by a select (std::fmax is a call), NaN to 0.
[[gnu::always_inline]] inline double nonneg(double x) { return x > 0.0 ? x : 0.0; }

// Cosine-weighted direction on the upper hemisphere (pdf cosθ/π) by Malley's method: a uniform point on
// the unit disk (radius √u1, azimuth φ) lifted to the hemisphere. This form takes cos φ and sin φ, for
// samplers that compute them their own (vectorisable) way.
[[gnu::always_inline]] inline Vec3 cosine_hemisphere(double u1, double cos_phi, double sin_phi) {
    const double r = std::sqrt(u1), z2 = 1.0 - u1;
    return {r * cos_phi, r * sin_phi, std::sqrt(z2 > 0.0 ? z2 : 0.0)};
}

// The cosine-weighted direction with the azimuth 2πu2 from turn(), and its density.
[[gnu::always_inline]] inline Vec3 cosine(double u1, double u2) {
    const runtime::kernels::SinCos phi = turn(u2);
    return cosine_hemisphere(u1, phi.c, phi.s);
}
[[gnu::always_inline]] inline double cosine_pdf(const Vec3& w) { return w.z > 0.0 ? w.z / kPi : 0.0; }

// Direction at polar angle cosine c (around +z) and azimuth 2π u.
[[gnu::always_inline]] inline Vec3 around_z(double c, double u) {
    const double s = std::sqrt(nonneg(1.0 - c * c));
    const runtime::kernels::SinCos phi = turn(u);
    return {s * phi.c, s * phi.s, c};
}

// Half-vector samplers draw h from an isotropic (or φ → φ+π symmetric) density p_h over the upper
// hemisphere. An h facing away from wo is turned half a revolution about the normal, which faces it
// toward wo (wo·h' = 2 cosθo cosθh − wo·h > 0); that half of p_h's mass lands on h' too.
inline Vec3 reflect_about_drawn_half(const Vec3& wo, Vec3 h) {
    if (!(dot(wo, h) > 0.0)) h = {-h.x, -h.y, h.z};
    return reflect(wo, h);
}

// The density over wi of reflect_about_drawn_half, given p_h at w's half vector.
template <typename HalfDensity>
double reflected_density(const Vec3& wo, const Vec3& w, HalfDensity&& p_h) {
    Vec3 h;
    if (!half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
    const double folded = dot(wo, Vec3{-h.x, -h.y, h.z}) > 0.0 ? 1.0 : 2.0;
    return folded * p_h(h) / (4.0 * dot(wo, h));
}

// Solves cdf(x) = target on [lo, hi] for an increasing cdf, by Newton steps kept inside a shrinking
// bracket (bisection when a step would leave it). `eval(x, c, d)` sets c = cdf(x) and d = cdf'(x).
template <typename Eval>
double invert_cdf(Eval&& eval, double target, double lo, double hi, double x) {
    for (int it = 0; it < 100; ++it) {
        double c, d;
        eval(x, c, d);
        if (c == target) return x;
        (c > target ? hi : lo) = x;
        double next = x - (c - target) / d;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::fabs(next - x) <= 1e-13 * std::fmax(1.0, std::fabs(x)) || !(hi - lo > 1e-14)) return next;
        x = next;
    }
    return x;
}

}  // namespace brdfz::lobes::sampling
