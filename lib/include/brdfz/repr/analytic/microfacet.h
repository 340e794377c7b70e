// Microfacet building blocks, templated on the scalar type so one implementation serves double / float
// evaluation and ceres::Jet autodiff. Angles enter as cosines; callers guarantee the ranges noted.
#pragma once

#include <cmath>
#include <numbers>

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

}  // namespace brdfz::microfacet
