// Microfacet building blocks, templated on the scalar type so one implementation serves double / float
// evaluation and ceres::Jet autodiff. Angles enter as cosines; callers guarantee the ranges noted.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

namespace brdfz::microfacet {

// GGX / Trowbridge-Reitz normal distribution, normalised so ∫ D cosθm dωm = 1. cos_m in [0, 1].
template <typename T>
T ggx_d(const T& cos_m, const T& alpha) {
    const T a2 = alpha * alpha;
    const T c2 = cos_m * cos_m;
    const T k = c2 * (a2 - T(1)) + T(1);
    return a2 / (T(lobes::kPi) * k * k);
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
    return exp(-((S(1) - c2) / c2) / a2) / (T(lobes::kPi) * a2 * (c2 * c2));
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
    return T(1) / (T(lobes::kPi) * ax * ay * k * k);
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

// --- Sampling visible normals (the lobes' sample and pdf) ----------------------------------------
// GGX: visible normals of the stretched (α = 1) configuration are uniform on a spherical cap seen from
// the stretched wo; stretching the cap point back gives h (Dupuy & Benyoub 2023). Their density is
// D_wo(h) = G1(wo) (wo·h) D(h) / cosθo, so pdf(wi) = D_wo(h) / (4 wo·h) = D(h) / (2 (cosθo + L)),
// L = √(cos²θo + αx² wo.x² + αy² wo.y²), with the exact Smith G1 = 2 cosθo / (cosθo + L).
[[gnu::always_inline]] inline Vec3 ggx_visible_sample(const Vec3& wo, double ax, double ay, double u1, double u2) {
    const Vec3 v = normalize({ax * wo.x, ay * wo.y, wo.z});
    const double z = (1.0 - u2) * (1.0 + v.z) - v.z;
    const Vec3 c = lobes::sampling::around_z(z, u1);
    const Vec3 hs = c + v;
    const Vec3 h = normalize({ax * hs.x, ay * hs.y, hs.z});
    return lobes::sampling::reflect(wo, h);
}

[[gnu::always_inline]] inline double ggx_visible_pdf(const Vec3& wo, const Vec3& w, double ax, double ay) {
    Vec3 h;
    if (!lobes::sampling::half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
    const double l = std::sqrt(wo.z * wo.z + ax * ax * wo.x * wo.x + ay * ay * wo.y * wo.y);
    return ggx_aniso_d(h.x, h.y, h.z, ax, ay) / (2.0 * (wo.z + l));
}

// Beckmann (Heitz & d'Eon 2014): in the stretched configuration (α = 1, wo at polar angle θ in the
// xz-plane) slopes (x, y) of visible normals m ∝ (−x, −y, 1) have density ∝ exp(−x² − y²)
// (cosθ − x sinθ) for x < cotθ: y is normal with variance ½, and x has the CDF ∝ M(x) = ½ cosθ erfc(−x)
// + sinθ exp(−x²) / (2√π), whose total M(cotθ) = cosθ (1 + Λ(θ)). Both are inverted numerically to
// 1e-13. pdf(wi) = D(h) / (4 cosθo (1 + Λ(wo))) with the exact Λ; cosθo (1 + Λ) = M(cotθo) at α is
// written without dividing by cosθo or sinθo, so it stays finite at the pole and at grazing.
inline constexpr double kInvSqrtPi = 0.56418958354775628695;  // 1/√π
inline constexpr double kSlopeRange = 8.0;  // |slope| beyond 8 (in α units) carries e^-64 of the mass

// Winitzki's closed-form approximation of erf⁻¹(2u − 1) (relative error < 2e-3): a starting point
// from which Newton needs about three steps. 1 − z² is formed as 4u(1 − u) to keep the tails exact.
inline double inverse_erf_guess(double u) {
    constexpr double a = 0.147;
    const double l = std::log(4.0 * u * (1.0 - u)), t = 2.0 / (lobes::kPi * a) + 0.5 * l;
    return std::clamp(std::copysign(std::sqrt(std::sqrt(t * t - l / a) - t), u - 0.5), -kSlopeRange, kSlopeRange);
}

inline double beckmann_visible_norm(const Vec3& wo, double alpha) {
    const double s = std::sqrt(wo.x * wo.x + wo.y * wo.y), a = wo.z / (alpha * s);  // a = ∞ at the pole
    return 0.5 * wo.z * std::erfc(-a) + alpha * s * std::exp(-a * a) * (0.5 * kInvSqrtPi);
}

inline Vec3 beckmann_visible_sample(const Vec3& wo, double alpha, double u1, double u2) {
    const Vec3 v = normalize({alpha * wo.x, alpha * wo.y, wo.z});
    const double sin_v = std::sqrt(v.x * v.x + v.y * v.y), cos_v = v.z;
    const double hi = sin_v > 0.0 ? std::fmin(cos_v / sin_v, kSlopeRange) : kSlopeRange;
    const auto m = [&](double x, double& c, double& d) {
        const double g = std::exp(-x * x);
        c = 0.5 * cos_v * std::erfc(-x) + sin_v * g * (0.5 * kInvSqrtPi);
        d = g * (cos_v - x * sin_v) * kInvSqrtPi;
    };
    double m_hi, unused;
    m(hi, m_hi, unused);
    // Start between the two limits: a normal slope at the pole, −√(−ln u) (CDF exp(−x²)) at grazing.
    const double t = sin_v * sin_v;
    const double guess = (1.0 - t) * inverse_erf_guess(u1) - t * std::sqrt(-std::log(std::fmax(u1, 1e-300)));
    const double x = lobes::sampling::invert_cdf(m, u1 * m_hi, -kSlopeRange, hi, std::clamp(guess, -kSlopeRange, hi));
    const auto gauss = [](double y, double& c, double& d) {
        c = 0.5 * std::erfc(-y);
        d = std::exp(-y * y) * kInvSqrtPi;
    };
    const double y = lobes::sampling::invert_cdf(gauss, u2, -kSlopeRange, kSlopeRange, inverse_erf_guess(u2));
    // Rotate the slopes to wo's azimuth and unstretch them.
    const double cp = sin_v > 0.0 ? v.x / sin_v : 1.0, sp = sin_v > 0.0 ? v.y / sin_v : 0.0;
    const Vec3 h = normalize({-alpha * (cp * x - sp * y), -alpha * (sp * x + cp * y), 1.0});
    return lobes::sampling::reflect(wo, h);
}

inline double beckmann_visible_pdf(const Vec3& wo, const Vec3& w, double alpha) {
    Vec3 h;
    if (!lobes::sampling::half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
    return beckmann_d(h.z, alpha) / (4.0 * beckmann_visible_norm(wo, alpha));
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

inline constexpr std::array<ParamSpec, 4> kSpecularWeightsAndAlpha{{
    {"ks_r", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"ks_g", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"ks_b", 0.0, 1.0, 1.0, ParamKind::Weight},
    {"alpha", 1e-3, 1.0, 0.2, ParamKind::LogScale},
}};

}  // namespace detail

// Distribution and masking-shadowing: dv(g, α) = D(h) · G2 / (4 cosθi cosθo); sample and pdf draw
// wi by the distribution's visible normals.
struct GgxVisibleNormals {
    static Vec3 sample(const Vec3& wo, double alpha, double u1, double u2) {
        return microfacet::ggx_visible_sample(wo, alpha, alpha, u1, u2);
    }
    static double pdf(const Vec3& wo, const Vec3& w, double alpha) {
        return microfacet::ggx_visible_pdf(wo, w, alpha, alpha);
    }
};
struct GgxCorrelated : GgxVisibleNormals {
    template <typename T, typename S>
    static T dv(const Geometry<S>& g, const T& alpha) {
        return microfacet::ggx_d(T(g.hz), alpha) * microfacet::ggx_visibility_correlated(g.iz, g.oz, alpha);
    }
};
struct GgxSeparable : GgxVisibleNormals {
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
    static Vec3 sample(const Vec3& wo, double alpha, double u1, double u2) {
        return microfacet::beckmann_visible_sample(wo, alpha, u1, u2);
    }
    static double pdf(const Vec3& wo, const Vec3& w, double alpha) { return microfacet::beckmann_visible_pdf(wo, w, alpha); }
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

// Parameters: ks_r, ks_g, ks_b, alpha, then the Fresnel term's. The families below derive from it and
// add their name.
template <typename Distribution, typename Fresnel>
struct Microfacet {
    static constexpr bool linear_weights = true;
    static constexpr auto params = detail::concat(detail::kSpecularWeightsAndAlpha, Fresnel::params);

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        const T dv = Distribution::dv(g, p[3]);
        T f[3];
        Fresnel::eval(g.d, p + 4, f);
        for (int c = 0; c < 3; ++c) out[c] = p[c] * f[c] * dv;
    }
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        return Distribution::sample(wo, p[3], u1, u2);
    }
    static double pdf(const double* p, const Vec3& wo, const Vec3& w) { return Distribution::pdf(wo, w, p[3]); }
};

struct Ggx : Microfacet<GgxCorrelated, Schlick> {
    static constexpr std::string_view name = "ggx";
};
struct GgxDielectric : Microfacet<GgxCorrelated, Dielectric> {
    static constexpr std::string_view name = "ggx_dielectric";
};
struct GgxConductor : Microfacet<GgxCorrelated, Conductor> {
    static constexpr std::string_view name = "ggx_conductor";
};
// Separable masking, to match renderers that use it (Mitsuba 3).
struct GgxSep : Microfacet<GgxSeparable, Schlick> {
    static constexpr std::string_view name = "ggx_sep";
};
struct GgxDielectricSep : Microfacet<GgxSeparable, Dielectric> {
    static constexpr std::string_view name = "ggx_dielectric_sep";
};
struct GgxConductorSep : Microfacet<GgxSeparable, Conductor> {
    static constexpr std::string_view name = "ggx_conductor_sep";
};
struct Beckmann : Microfacet<BeckmannSeparable, Schlick> {
    static constexpr std::string_view name = "beckmann";
};
struct BeckmannDielectric : Microfacet<BeckmannSeparable, Dielectric> {
    static constexpr std::string_view name = "beckmann_dielectric";
};
struct BeckmannConductor : Microfacet<BeckmannSeparable, Conductor> {
    static constexpr std::string_view name = "beckmann_conductor";
};

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
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        return microfacet::ggx_visible_sample(wo, p[3], p[4], u1, u2);
    }
    static double pdf(const double* p, const Vec3& wo, const Vec3& w) {
        return microfacet::ggx_visible_pdf(wo, w, p[3], p[4]);
    }
};

}  // namespace brdfz::lobes
