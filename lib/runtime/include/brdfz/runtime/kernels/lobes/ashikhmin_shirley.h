// Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (JGT 2000): an anisotropic Phong specular
// lobe with Schlick Fresnel, and the matching diffuse term that takes the energy the specular layer
// leaves, as one lobe (the two share Rs):
//   spec = √((nu+1)(nv+1)) / (8π) · cosθh^e / ((wi·h) max(cosθi, cosθo)) · F(wi·h),
//          e = (nu hx² + nv hy²) / (1 − hz²),   F = Rs + (1 − Rs)(1 − wi·h)⁵
//   diff = 28 Rd / (23π) · (1 − Rs) · (1 − (1 − cosθi/2)⁵) · (1 − (1 − cosθo/2)⁵)
// nu along the tangent +x. Reciprocal. The specular distribution is normalised as a density of h, so
// its albedo is at most 1; the diffuse term's is about Rd (1 − Rs).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

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
        const T spec = sqrt((nu + T(1)) * (nv + T(1))) * T(0.125 * kInvPi) * exp(e * log_cos) / denom;
        const S m = S(1) - g.d, schlick = m * m * m * m * m;
        const auto fifth = [](S x) { return x * x * x * x * x; };
        const S diff_shape = (S(1) - fifth(S(1) - g.iz / S(2))) * (S(1) - fifth(S(1) - g.oz / S(2)));
        for (int c = 0; c < 3; ++c) {
            const T& rd = p[c];
            const T& rs = p[3 + c];
            const T fresnel = rs + (T(1) - rs) * schlick;
            out[c] = spec * fresnel + T(28.0 / 23.0 * kInvPi) * rd * (T(1) - rs) * diff_shape;
        }
    }

    // The paper's specular density p_h = √((nu+1)(nv+1))/(2π) cosθh^(nu cos²φ + nv sin²φ) (sampled by its
    // closed-form inversion), or cosine sampling for the diffuse part. The share of the specular part is
    // its albedo over the total by a closed-form estimate: Fresnel averaged over the cosine-weighted
    // hemisphere, Rs + (1 − Rs)/21, against the diffuse term's Rd (1 − Rs), both averaged over channels.
    static double specular_share(const double* p) {
        double spec = 0.0, diff = 0.0;
        for (int c = 0; c < 3; ++c) {
            spec += p[3 + c] + (1.0 - p[3 + c]) / 21.0;
            diff += p[c] * (1.0 - p[3 + c]);
        }
        return spec / (spec + diff);
    }
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double share = specular_share(p);
        if (!(u1 < share)) return sampling::cosine(std::fmin((u1 - share) / (1.0 - share), std::nextafter(1.0, 0.0)), u2);
        // φ in one quadrant by the paper's inversion, the quadrant from the top two bits of u.
        const double v = 4.0 * u1 / share;
        const int quadrant = std::min(static_cast<int>(v), 3);
        const double phi0 = std::atan(std::sqrt((p[6] + 1.0) / (p[7] + 1.0)) * std::tan(0.5 * kPi * (v - quadrant)));
        const double phi = quadrant == 0 ? phi0 : quadrant == 1 ? kPi - phi0 : quadrant == 2 ? kPi + phi0 : 2.0 * kPi - phi0;
        const double cp = std::cos(phi), sp = std::sin(phi);
        const double e = p[6] * cp * cp + p[7] * sp * sp;
        const double c = std::exp(std::log1p(-u2) / (e + 1.0)), s = std::sqrt(std::fmax(0.0, 1.0 - c * c));
        return sampling::reflect_about_drawn_half(wo, {s * cp, s * sp, c});
    }
    static double pdf(const double* p, const Vec3& wo, const Vec3& w) {
        const double share = specular_share(p);
        const double nu = p[6], nv = p[7];
        const double spec = sampling::reflected_density(wo, w, [nu, nv](const Vec3& h) {
            const double xy = std::fmax(h.x * h.x + h.y * h.y, kTiny);
            const double e = (nu * h.x * h.x + nv * h.y * h.y) / xy;
            return std::sqrt((nu + 1.0) * (nv + 1.0)) * (0.5 / kPi) * std::exp(e * std::log(h.z));
        });
        return share * spec + (1.0 - share) * sampling::cosine_pdf(w);
    }
};

}  // namespace brdfz::lobes
