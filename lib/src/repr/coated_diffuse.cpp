#include "brdfz/repr/analytic/coated_diffuse.h"

#include <cstdio>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/runtime/kernels/lobes/microfacet.h"

namespace brdfz {

CoatedDiffuse::CoatedDiffuse(CoatedDiffuseParams p) : p_(p) {
    if (!(p_.alpha > 0.0 && p_.alpha <= 1.0)) throw ValueError("coated diffuse: alpha must be in (0, 1]");
    if (!(p_.eta >= 1.0 && p_.eta <= 4.0)) throw ValueError("coated diffuse: eta must be in [1, 4]");
    for (double a : p_.base_albedo)
        if (!(a >= 0.0 && a <= 1.0)) throw ValueError("coated diffuse: base albedo must be in [0, 1]");
}

std::string CoatedDiffuse::describe() const {
    char buf[160];
    std::snprintf(buf, sizeof buf, "coated diffuse: GGX coat alpha=%.3g eta=%.3g over base albedo (%.3g, %.3g, %.3g)",
                  p_.alpha, p_.eta, p_.base_albedo[0], p_.base_albedo[1], p_.base_albedo[2]);
    return buf;
}

Rgb CoatedDiffuse::eval_above(const Vec3& wi, const Vec3& wo) const {
    using namespace microfacet;
    const Vec3 h = half_vector(wi, wo);
    const double cos_d = std::fmax(dot(wi, h), 0.0);
    // The denominator underflows for (sub)normal cosines; G2 vanishes there first, so the lobe is 0.
    const double denom = 4.0 * wi.z * wo.z;
    const double spec =
        denom > 0.0 ? fresnel_dielectric(cos_d, p_.eta) * ggx_d(h.z, p_.alpha) * ggx_g2(wi.z, wo.z, p_.alpha) / denom
                    : 0.0;
    const double trans = (1.0 - fresnel_dielectric(wi.z, p_.eta)) * (1.0 - fresnel_dielectric(wo.z, p_.eta));
    Rgb f;
    for (int c = 0; c < 3; ++c) f[c] = spec + trans * p_.base_albedo[c] / std::numbers::pi;
    return f;
}

}  // namespace brdfz
