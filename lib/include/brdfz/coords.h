// Rusinkiewicz half/difference coordinates (Rusinkiewicz 1998) <-> direction pairs.
//
// h = normalize(wi + wo) has polar angles (θh, φh). The difference vector d is wi expressed in the
// frame obtained by rotating the local frame by -φh about z and then by -θh about y (MERL's
// convention), with polar angles (θd, φd). wo is wi rotated by π about h.
#pragma once

#include <cmath>
#include <utility>

#include "brdfz/frame.h"

namespace brdfz {

struct HalfDiff {
    double theta_h = 0;  // [0, π]
    double phi_h = 0;    // (-π, π]
    double theta_d = 0;  // [0, π]
    double phi_d = 0;    // (-π, π]
};

// The orthonormal frame (t, b, h) around a half vector h; t and b follow MERL's rotations, so that
// d = (dot(wi, t), dot(wi, b), dot(wi, h)). At the pole (h = ẑ) this is the identity frame.
struct HalfFrame {
    Vec3 t, b, h;
};
inline HalfFrame half_frame(const Vec3& h) {
    // sinθh = ‖h_xy‖, cosθh = h.z, and (cosφh, sinφh) = h_xy / ‖h_xy‖: no trigonometric calls.
    const double r = std::sqrt(h.x * h.x + h.y * h.y);
    const double cos_phi = r > 0.0 ? h.x / r : 1.0;
    const double sin_phi = r > 0.0 ? h.y / r : 0.0;
    const double cos_theta = h.z, sin_theta = r;
    return {{cos_theta * cos_phi, cos_theta * sin_phi, -sin_theta}, {-sin_phi, cos_phi, 0.0}, h};
}

// Half vector of a direction pair. Finite for every pair: opposite directions (wi = -wo, possible
// only at grazing) have no unique half vector and get the normal ẑ, the only choice that keeps h in
// the upper hemisphere.
inline Vec3 half_vector(const Vec3& wi, const Vec3& wo) {
    const Vec3 s = wi + wo;
    const double n2 = dot(s, s);
    if (!(n2 > 1e-300)) return {0.0, 0.0, 1.0};
    return (1.0 / std::sqrt(n2)) * s;
}

// wi in the half frame of (wi, wo): the difference vector, whose polar angles are (θd, φd).
inline Vec3 difference_vector(const Vec3& wi, const HalfFrame& f) { return {dot(wi, f.t), dot(wi, f.b), dot(wi, f.h)}; }

HalfDiff to_half_diff(const Vec3& wi, const Vec3& wo);

// {wi, wo} from half/difference angles.
std::pair<Vec3, Vec3> from_half_diff(const HalfDiff& hd);

}  // namespace brdfz
