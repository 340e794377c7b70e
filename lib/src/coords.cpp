#include "brdfz/coords.h"

#include <cmath>

namespace brdfz {

HalfDiff to_half_diff(const Vec3& wi, const Vec3& wo) {
    const Vec3 h = half_vector(wi, wo);
    const HalfFrame f = half_frame(h);
    const Vec3 d = difference_vector(wi, f);
    return {elevation(h), std::atan2(h.y, h.x), elevation(d), std::atan2(d.y, d.x)};
}

std::pair<Vec3, Vec3> from_half_diff(const HalfDiff& hd) {
    const Vec3 h = spherical_direction(hd.theta_h, hd.phi_h);
    const HalfFrame f = half_frame(h);
    const Vec3 d = spherical_direction(hd.theta_d, hd.phi_d);
    // wo is wi rotated by π about h: in the (t, b, h) frame that negates the t and b components.
    const Vec3 wi = d.x * f.t + d.y * f.b + d.z * f.h;
    const Vec3 wo = (-d.x) * f.t + (-d.y) * f.b + d.z * f.h;
    return {wi, wo};
}

}  // namespace brdfz
