// Generalised cosine lobe (Lafortune et al., "Non-linear approximation of reflectance functions",
// SIGGRAPH 1997), isotropic, with the normalisation of a Phong lobe of exponent n:
//   f = ρ · (n+2)/(2π) · max(0, cxy (wi.x wo.x + wi.y wo.y) + cz wi.z wo.z)^n
// cxy = −1, cz = 1 is a Phong lobe around the mirror direction, cxy = cz = 1 a retro-reflective lobe,
// cxy = 0 an off-specular lobe toward grazing. With |cxy|, |cz| <= 1 the base is at most 1 and the
// albedo at most ρ. Reciprocal. A model "lafortune3" sums three of them.
#pragma once

#include <array>
#include <cmath>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

namespace brdfz::lobes {

struct Lafortune {
    static constexpr std::string_view name = "lafortune";
    static constexpr bool linear_weights = true;
    static constexpr std::array<ParamSpec, 6> params{{
        {"rho_r", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rho_g", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rho_b", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"cxy", -1.0, 1.0, -1.0, ParamKind::Linear},
        {"cz", -1.0, 1.0, 1.0, ParamKind::Linear},
        {"n", 0.1, 1e4, 20.0, ParamKind::LogScale},
    }};

    template <typename T, typename S>
    static void eval(const Geometry<S>& g, const T* p, T out[3]) {
        using std::exp;
        using std::log;
        using std::fmax;
        const T& n = p[5];
        const T base = p[3] * (g.ix * g.ox + g.iy * g.oy) + p[4] * (g.iz * g.oz);
        // base^n as exp(n ln base), differentiable in n; the floor keeps the logarithm finite where the
        // select discards the value (base <= 0).
        const T power = exp(n * log(fmax(base, T(kTiny))));
        const T lobe = select(base > T(0), (n + T(2)) * T(0.5 * kInvPi) * power, T(0));
        for (int c = 0; c < 3; ++c) out[c] = p[c] * lobe;
    }

    // A cosine-power lobe (n+1)/(2π) (w·â)^n around â = a/|a|, a = (cxy wo.x, cxy wo.y, cz wo.z). The
    // lobe is |a|^n (wi·â)^n; where a vanishes so does the lobe, and cosine sampling stands in.
    static bool axis(const double* p, const Vec3& wo, Vec3& a) {
        a = {p[3] * wo.x, p[3] * wo.y, p[4] * wo.z};
        const double len = length(a);
        if (!(len > 1e-12)) return false;
        a = (1.0 / len) * a;
        return true;
    }
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        Vec3 a;
        if (!axis(p, wo, a)) return sampling::cosine(u1, u2);
        return sampling::Basis(a).to_world(sampling::around_z(std::exp(std::log1p(-u1) / (p[5] + 1.0)), u2));
    }
    static double pdf(const double* p, const Vec3& wo, const Vec3& w) {
        Vec3 a;
        if (!axis(p, wo, a)) return sampling::cosine_pdf(w);
        const double c = dot(w, a);
        return c > 0.0 ? (p[5] + 1.0) * (0.5 / kPi) * std::exp(p[5] * std::log(c)) : 0.0;
    }
};

}  // namespace brdfz::lobes
