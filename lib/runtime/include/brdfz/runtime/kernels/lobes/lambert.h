// Lambertian lobe: f = ρ / π per channel. Albedo ρ, reciprocal.
#pragma once

#include <array>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

namespace brdfz::lobes {

struct Lambert {
    static constexpr std::string_view name = "lambert";
    static constexpr bool linear_weights = true;
    static constexpr std::array<ParamSpec, 3> params{{
        {"rho_r", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rho_g", 0.0, 1.0, 0.5, ParamKind::Weight},
        {"rho_b", 0.0, 1.0, 0.5, ParamKind::Weight},
    }};

    template <typename T, typename S>
    static void eval(const Geometry<S>&, const T* p, T out[3]) {
        for (int c = 0; c < 3; ++c) out[c] = p[c] * T(kInvPi);
    }

    // Cosine-weighted on the upper hemisphere.
    static Vec3 sample(const double*, const Vec3&, double u1, double u2) { return sampling::cosine(u1, u2); }
    static double pdf(const double*, const Vec3&, const Vec3& w) { return sampling::cosine_pdf(w); }
};

}  // namespace brdfz::lobes
