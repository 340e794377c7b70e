// Microfacet building blocks, templated on the scalar type so one implementation serves double / float
// evaluation and ceres::Jet autodiff. Angles enter as cosines; callers guarantee the ranges noted.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string_view>

#include "brdfz/repr/analytic/lobe.h"

namespace brdfz::microfacet {

// GGX / Trowbridge-Reitz normal distribution, normalised so ∫ D cosθm dωm = 1. cos_m in [0, 1].
template <typename T>
T ggx_d(const T& cos_m, const T& alpha) {
    const T a2 = alpha * alpha;
    const T c2 = cos_m * cos_m;
    const T k = c2 * (a2 - T(1)) + T(1);
    return a2 / (T(std::numbers::pi) * k * k);
}

// Smith Λ for GGX; height-correlated masking-shadowing G2 = 1 / (1 + Λ(wi) + Λ(wo)). cos in (0, 1].
template <typename T>
T ggx_lambda(const T& cos_t, const T& alpha) {
    const T c2 = cos_t * cos_t;
    const T tan2 = (T(1) - c2) / c2;
    using std::sqrt;
    return (sqrt(T(1) + alpha * alpha * tan2) - T(1)) / T(2);
}

template <typename T>
T ggx_g2(const T& cos_i, const T& cos_o, const T& alpha) {
    return T(1) / (T(1) + ggx_lambda(cos_i, alpha) + ggx_lambda(cos_o, alpha));
}

// Unpolarised Fresnel reflectance of a dielectric interface with relative index eta, seen from the
// outside at incidence cosine cos_i in [0, 1]. Total internal reflection cannot occur from outside
// when eta >= 1; for eta < 1 it returns 1 past the critical angle.
template <typename T>
T fresnel_dielectric(const T& cos_i, const T& eta) {
    using std::sqrt;
    const T sin2_t = (T(1) - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= T(1)) return T(1);
    const T cos_t = sqrt(T(1) - sin2_t);
    const T rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const T rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return (rs * rs + rp * rp) / T(2);
}

// Beckmann normal distribution exp(−tan²θm / α²) / (π α² cos⁴θm). cos_m in (0, 1].
template <typename T, typename S>
T beckmann_d(const S& cos_m, const T& alpha) {
    using std::exp;
    const S c2 = std::max(cos_m * cos_m, S(kTiny));
    const T a2 = alpha * alpha;
    return exp(-((S(1) - c2) / c2) / a2) / (T(std::numbers::pi) * a2 * (c2 * c2));
}

// √(cos²θ (1−α²) + α²) = cosθ·√(1 + α² tan²θ), the root in GGX's Smith Λ and G1, from a2 = α².
template <typename T, typename S>
T ggx_smith_root(const S& cos_t, const T& a2) {
    using std::sqrt;
    return sqrt(cos_t * cos_t * (T(1) - a2) + a2);
}

// GGX "visibility" V = G2 / (4 cosθi cosθo) with the height-correlated Smith G2 written so it stays
// finite at grazing angles: 4 cosθi cosθo (1 + Λi + Λo) = 2 (cosθo·√(cos²θi (1−α²) + α²) + (i<->o)).
template <typename T, typename S>
T ggx_visibility_correlated(const S& cos_i, const S& cos_o, const T& alpha) {
    const T a2 = alpha * alpha;
    return T(0.5) / (cos_o * ggx_smith_root(cos_i, a2) + cos_i * ggx_smith_root(cos_o, a2) + T(kTiny));
}

// The same with the separable (uncorrelated) Smith G2 = G1(wi) G1(wo), G1 = 2cosθ / (cosθ + √(cos²θ (1−α²) + α²)),
// as Mitsuba 3 and Walter et al. 2007 use.
template <typename T, typename S>
T ggx_visibility_separable(const S& cos_i, const S& cos_o, const T& alpha) {
    const T a2 = alpha * alpha;
    return T(1) / ((cos_i + ggx_smith_root(cos_i, a2)) * (cos_o + ggx_smith_root(cos_o, a2)));
}

// Smith G1 for Beckmann by Walter et al.'s rational approximation (EGSR 2007, eq. 27; < 0.35% error),
// with a = 1 / (α tanθ). Mitsuba 3 uses the same approximation.
template <typename T, typename S>
T beckmann_g1(const S& cos_v, const T& alpha) {
    using std::sqrt;
    const S sin_v = sqrt(std::max(S(1) - cos_v * cos_v, S(kTiny) * S(kTiny)));
    const T a = (cos_v / sin_v) / alpha;
    const T g = (T(3.535) * a + T(2.181) * a * a) / (T(1) + T(2.276) * a + T(2.577) * a * a);
    return select(a < T(1.6), g, T(1));
}

template <typename T, typename S>
T beckmann_visibility_separable(const S& cos_i, const S& cos_o, const T& alpha) {
    // G1 ~ cosθ near grazing: dividing each factor by its own cosine keeps the quotient finite.
    return (beckmann_g1(cos_i, alpha) / std::max(cos_i, S(kTiny))) *
           (beckmann_g1(cos_o, alpha) / std::max(cos_o, S(kTiny))) * T(0.25);
}

// Anisotropic GGX distribution 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²).
template <typename T, typename S>
T ggx_aniso_d(const S& hx, const S& hy, const S& hz, const T& ax, const T& ay) {
    const T x = hx / ax, y = hy / ay;
    const T k = x * x + y * y + hz * hz;
    return T(1) / (T(std::numbers::pi) * ax * ay * k * k);
}

// Height-correlated anisotropic visibility: cosθ·√(1 + 2Λ...) becomes √(cos²θ + αx² vx² + αy² vy²).
template <typename T, typename S>
T ggx_aniso_visibility(const Geometry<S>& g, const T& ax, const T& ay) {
    using std::sqrt;
    const T ax2 = ax * ax, ay2 = ay * ay;
    const T li = sqrt(g.iz * g.iz + ax2 * (g.ix * g.ix) + ay2 * (g.iy * g.iy));
    const T lo = sqrt(g.oz * g.oz + ax2 * (g.ox * g.ox) + ay2 * (g.oy * g.oy));
    return T(0.5) / (g.oz * li + g.iz * lo + T(kTiny));
}

// Schlick's approximation F0 + (1 − F0)(1 − cosθ)⁵.
template <typename T, typename S>
T fresnel_schlick(const S& cos_d, const T& f0) {
    const S m = S(1) - cos_d, m2 = m * m;
    return f0 + (T(1) - f0) * (m2 * m2 * m);
}

// Unpolarised Fresnel reflectance of a conductor with complex index eta + i·k (relative to the outside
// medium), exact, at incidence cosine cos_i in [0, 1]. The usual closed form via a² + b² (Born & Wolf).
template <typename T, typename S>
T fresnel_conductor(const S& cos_i, const T& eta, const T& k) {
    using std::fmax;
    using std::sqrt;
    const S c2 = cos_i * cos_i, s2 = S(1) - c2, s4 = s2 * s2;
    const T t0 = eta * eta - k * k - s2;
    // Floors keep the square roots differentiable where a and a² + b² vanish (k = 0 past the critical
    // angle of an eta < 1 dielectric), at a relative cost far below float precision.
    const T a2b2 = sqrt(fmax(t0 * t0 + T(4) * eta * eta * k * k, T(kTiny * kTiny)));
    const T a = sqrt(fmax(T(0.5) * (a2b2 + t0), T(kTiny)));
    const T t1 = a2b2 + c2, t2 = T(2) * cos_i * a;
    const T rs = (t1 - t2) / (t1 + t2);
    const T t3 = a2b2 * c2 + s4, t4 = t2 * s2;
    const T rp = rs * (t3 - t4) / (t3 + t4);
    return T(0.5) * (rs + rp);
}

}  // namespace brdfz::microfacet

// Microfacet lobes f = ks · F(wi·h) · D(h) · G2 / (4 cosθi cosθo): reciprocal, and energy-conserving
// for ks <= 1 (F <= 1 and Smith G2 account for the light the microsurface sends back).
namespace brdfz::lobes {

namespace detail {

template <std::size_t A, std::size_t B>
constexpr std::array<ParamSpec, A + B> concat(const std::array<ParamSpec, A>& a, const std::array<ParamSpec, B>& b) {
    std::array<ParamSpec, A + B> out{};
    for (std::size_t i = 0; i < A; ++i) out[i] = a[i];
    for (std::size_t i = 0; i < B; ++i) out[A + i] = b[i];
    return out;
}

// A string literal usable as a template argument, so each lobe's name is part of its type.
template <std::size_t N>
struct Name {
    char text[N];
    constexpr Name(const char (&s)[N]) {
        for (std::size_t i = 0; i < N; ++i) text[i] = s[i];
    }
    constexpr std::string_view view() const { return {text, N - 1}; }
};

inline constexpr std::array<ParamSpec, 4> kSpecularWeightsAndAlpha{{
    {"ks_r", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"ks_g", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"ks_b", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"alpha", 1e-3, 1.0, 0.2, ParamKind::LogScale},
}};

}  // namespace detail

// Distribution and masking-shadowing: dv(g, α) = D(h) · G2 / (4 cosθi cosθo).
struct GgxCorrelated {
    template <typename T, typename S>
    static T dv(const Geometry<S>& g, const T& alpha) {
        return microfacet::ggx_d(T(g.hz), alpha) * microfacet::ggx_visibility_correlated(g.iz, g.oz, alpha);
    }
};
struct GgxSeparable {
    template <typename T, typename S>
    static T dv(const Geometry<S>& g, const T& alpha) {
        return microfacet::ggx_d(T(g.hz), alpha) * microfacet::ggx_visibility_separable(g.iz, g.oz, alpha);
    }
};
struct BeckmannSeparable {
    template <typename T, typename S>
    static T dv(const Geometry<S>& g, const T& alpha) {
        return microfacet::beckmann_d(g.hz, alpha) * microfacet::beckmann_visibility_separable(g.iz, g.oz, alpha);
    }
};

// Fresnel terms: their parameters and F per channel at cosθ = wi·h.
struct Schlick {
    static constexpr std::array<ParamSpec, 1> params{{{"f0", 0.0, 1.0, 0.04, ParamKind::Linear}}};
    template <typename T, typename S>
    static void eval(const S& cos_d, const T* p, T f[3]) {
        f[0] = f[1] = f[2] = microfacet::fresnel_schlick(cos_d, p[0]);
    }
};
struct Dielectric {
    static constexpr std::array<ParamSpec, 1> params{{{"eta", 1.0, 3.0, 1.5, ParamKind::Linear}}};
    template <typename T, typename S>
    static void eval(const S& cos_d, const T* p, T f[3]) {
        f[0] = f[1] = f[2] = microfacet::fresnel_dielectric(T(cos_d), p[0]);
    }
};
struct Conductor {
    // Defaults near gold at (650, 550, 450) nm.
    static constexpr std::array<ParamSpec, 6> params{{
        {"eta_r", 0.01, 6.0, 0.18, ParamKind::LogScale},
        {"eta_g", 0.01, 6.0, 0.42, ParamKind::LogScale},
        {"eta_b", 0.01, 6.0, 1.37, ParamKind::LogScale},
        {"k_r", 0.0, 12.0, 3.42, ParamKind::Linear},
        {"k_g", 0.0, 12.0, 2.35, ParamKind::Linear},
        {"k_b", 0.0, 12.0, 1.77, ParamKind::Linear},
    }};
    template <typename T, typename S>
    static void eval(const S& cos_d, const T* p, T f[3]) {
        for (int c = 0; c < 3; ++c) f[c] = microfacet::fresnel_conductor(cos_d, p[c], p[3 + c]);
    }
};

// Parameters: ks_r, ks_g, ks_b, alpha, then the Fresnel term's.
template <typename Distribution, typename Fresnel, detail::Name kName>
struct Microfacet {
    static constexpr std::string_view name = kName.view();
    static constexpr bool linear_weights = true;
    static constexpr auto params = detail::concat(detail::kSpecularWeightsAndAlpha, Fresnel::params);

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        const T dv = Distribution::dv(g, p[3]);
        T f[3];
        Fresnel::eval(g.d, p + 4, f);
        for (int c = 0; c < 3; ++c) out[c] = p[c] * f[c] * dv;
    }
};

using Ggx = Microfacet<GgxCorrelated, Schlick, "ggx">;
using GgxDielectric = Microfacet<GgxCorrelated, Dielectric, "ggx_dielectric">;
using GgxConductor = Microfacet<GgxCorrelated, Conductor, "ggx_conductor">;
// Separable masking, to match renderers that use it (Mitsuba 3).
using GgxSep = Microfacet<GgxSeparable, Schlick, "ggx_sep">;
using GgxDielectricSep = Microfacet<GgxSeparable, Dielectric, "ggx_dielectric_sep">;
using GgxConductorSep = Microfacet<GgxSeparable, Conductor, "ggx_conductor_sep">;
using Beckmann = Microfacet<BeckmannSeparable, Schlick, "beckmann">;
using BeckmannDielectric = Microfacet<BeckmannSeparable, Dielectric, "beckmann_dielectric">;
using BeckmannConductor = Microfacet<BeckmannSeparable, Conductor, "beckmann_conductor">;

// Anisotropic GGX with height-correlated masking and Schlick Fresnel; αx along the tangent +x.
struct GgxAniso {
    static constexpr std::string_view name = "ggx_aniso";
    static constexpr bool linear_weights = true;
    static constexpr std::array<ParamSpec, 6> params{{
        {"ks_r", 0.0, 1.0, 1.0, ParamKind::Weight},
        {"ks_g", 0.0, 1.0, 1.0, ParamKind::Weight},
        {"ks_b", 0.0, 1.0, 1.0, ParamKind::Weight},
        {"alpha_x", 1e-3, 1.0, 0.2, ParamKind::LogScale},
        {"alpha_y", 1e-3, 1.0, 0.2, ParamKind::LogScale},
        {"f0", 0.0, 1.0, 0.04, ParamKind::Linear},
    }};

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        const T dv = microfacet::ggx_aniso_d(g.hx, g.hy, g.hz, p[3], p[4]) * microfacet::ggx_aniso_visibility(g, p[3], p[4]);
        const T f = microfacet::fresnel_schlick(g.d, p[5]);
        for (int c = 0; c < 3; ++c) out[c] = p[c] * f * dv;
    }
};

}  // namespace brdfz::lobes
