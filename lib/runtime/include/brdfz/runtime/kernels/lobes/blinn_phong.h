// Normalised Blinn-Phong lobe: the Blinn-Phong normal distribution D(h) = (n+2)/(2π) cos^n θh, which
// integrates to 1 against cosθh, over the microfacet Jacobian's 4:
//   f = ks · (n+2)/(8π) · cos^n θh
// Reciprocal. Its directional albedo approaches ks from below as n grows (≈ 0.26 ks at n = 0.1,
// 0.96 ks at n = 100), so ks <= 1 conserves energy.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

namespace brdfz::lobes {

struct BlinnPhong {
    static constexpr std::string_view name = "blinn_phong";
    static constexpr bool linear_weights = true;
    static constexpr std::array<ParamSpec, 4> params{{
        {"ks_r", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"ks_g", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"ks_b", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"n", 0.1, 1e5, 50.0, ParamKind::LogScale},
    }};

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        using std::exp;
        using std::log;
        const T& n = p[3];
        // cos^n θh as exp(n ln cosθh): one form for every n, differentiable in n.
        const S log_cos = log(std::max(g.hz, S(kTiny)));
        const T lobe = (n + T(2)) * T(0.125 * kInvPi) * exp(n * log_cos);
        for (int c = 0; c < 3; ++c) out[c] = p[c] * lobe;
    }

    // h from p_h = (n+2)/(2π) cos^(n+1) θh, cosθh = u^(1/(n+2)), reflected about it.
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double c = std::exp(std::log1p(-u1) / (p[3] + 2.0));
        return sampling::reflect_about_drawn_half(wo, sampling::around_z(c, u2));
    }
    static double pdf(const double* p, const Vec3& wo, const Vec3& w) {
        const double n = p[3];
        return sampling::reflected_density(wo, w, [n](const Vec3& h) {
            return (n + 2.0) * (0.5 / kPi) * std::exp((n + 1.0) * std::log(h.z));
        });
    }
};

}  // namespace brdfz::lobes
