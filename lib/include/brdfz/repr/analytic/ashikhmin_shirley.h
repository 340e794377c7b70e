// Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (JGT 2000): an anisotropic Phong specular
// lobe with Schlick Fresnel, and the matching diffuse term that takes the energy the specular layer
// leaves, as one lobe (the two share Rs):
//   spec = √((nu+1)(nv+1)) / (8π) · cosθh^e / ((wi·h) max(cosθi, cosθo)) · F(wi·h),
//          e = (nu hx² + nv hy²) / (1 − hz²),   F = Rs + (1 − Rs)(1 − wi·h)⁵
//   diff = 28 Rd / (23π) · (1 − Rs) · (1 − (1 − cosθi/2)⁵) · (1 − (1 − cosθo/2)⁵)
// nu along the tangent +x. Reciprocal. The specular distribution is normalised as a density of h, so
// its albedo is at most 1; the diffuse term's is about Rd (1 − Rs).
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <string_view>

#include "brdfz/repr/analytic/lobe.h"

namespace brdfz::lobes {

struct AshikhminShirley {
    static constexpr std::string_view name = "ashikhmin_shirley";
    // Rs enters both terms non-linearly, so the weights are not plain scale factors.
    static constexpr bool linear_weights = false;
    static constexpr std::array<ParamSpec, 8> params{{
        {"rd_r", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rd_g", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rd_b", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rs_r", 0.0, 1.0, 0.05, ParamKind::Weight},
        {"rs_g", 0.0, 1.0, 0.05, ParamKind::Weight},
        {"rs_b", 0.0, 1.0, 0.05, ParamKind::Weight},
        {"nu", 1.0, 1e5, 100.0, ParamKind::LogScale},
        {"nv", 1.0, 1e5, 100.0, ParamKind::LogScale},
    }};

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        using std::exp;
        using std::log;
        using std::sqrt;
        const T& nu = p[6];
        const T& nv = p[7];
        // 1 − hz² = hx² + hy² for a unit h; the floor covers h = ẑ, where cosθh^e = 1 for any e.
        const S xy = std::max(g.hx * g.hx + g.hy * g.hy, S(kTiny));
        const T e = (nu * (g.hx * g.hx) + nv * (g.hy * g.hy)) / xy;
        const S log_cos = log(std::max(g.hz, S(kTiny)));
        const S denom = std::max(g.d, S(kTiny)) * std::max(std::max(g.iz, g.oz), S(kTiny));
        const T spec = sqrt((nu + T(1)) * (nv + T(1))) * T(0.125 * std::numbers::inv_pi) * exp(e * log_cos) / denom;
        const S m = S(1) - g.d, schlick = m * m * m * m * m;
        const auto fifth = [](S x) { return x * x * x * x * x; };
        const S diff_shape = (S(1) - fifth(S(1) - g.iz / S(2))) * (S(1) - fifth(S(1) - g.oz / S(2)));
        for (int c = 0; c < 3; ++c) {
            const T& rd = p[c];
            const T& rs = p[3 + c];
            const T fresnel = rs + (T(1) - rs) * schlick;
            out[c] = spec * fresnel + T(28.0 / 23.0 * std::numbers::inv_pi) * rd * (T(1) - rs) * diff_shape;
        }
    }
};

}  // namespace brdfz::lobes
