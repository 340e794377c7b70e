// Shared by the data-driven samplers (sample/halfvector.cpp, sample/factor_sampler.cpp): wo's frame
// about the normal, and mirror reflection about a half vector.
#pragma once

#include <cmath>

#include "brdfz/frame.h"

namespace brdfz::detail {

// wo's azimuth as a rotation (cos, sin); the identity at the pole.
struct Azimuth {
    double c = 1.0, s = 0.0;
    explicit Azimuth(const Vec3& w) : Azimuth(w, std::sqrt(w.x * w.x + w.y * w.y)) {}
    // With r = ‖w_xy‖ already at hand.
    Azimuth(const Vec3& w, double r) {
        if (r > 0.0) c = w.x / r, s = w.y / r;
    }
    Vec3 to_local(const Vec3& v) const { return {c * v.x + s * v.y, -s * v.x + c * v.y, v.z}; }
    Vec3 to_world(const Vec3& v) const { return {c * v.x - s * v.y, s * v.x + c * v.y, v.z}; }
};

inline Vec3 reflect(const Vec3& wo, const Vec3& h) { return (2.0 * dot(wo, h)) * h - wo; }

}  // namespace brdfz::detail
