// Local-frame helpers shared by every representation (the vector type and elevation() are the runtime's,
// brdfz/runtime/vec.h).
//
// The local shading frame has the surface normal on +z; see brdf.h for the full conventions.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/runtime/vec.h"

namespace brdfz {

// Spherical direction with polar angle theta from +z and azimuth phi from +x.
inline Vec3 spherical_direction(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// Cosine-weighted direction on the upper hemisphere (pdf cosθ/π) by Malley's method: a uniform point on
// the unit disk (radius √u1, azimuth φ) lifted to the hemisphere. This form takes cos φ and sin φ, for
// samplers that compute them their own (vectorisable) way; always inlined, since a call in a loop over
// lanes stops the vectoriser.
[[gnu::always_inline]] inline Vec3 cosine_hemisphere(double u1, double cos_phi, double sin_phi) {
    const double r = std::sqrt(u1), z2 = 1.0 - u1;
    return {r * cos_phi, r * sin_phi, std::sqrt(z2 > 0.0 ? z2 : 0.0)};
}

// The same from u1, u2 in [0, 1), azimuth 2π·u2.
inline Vec3 cosine_hemisphere(double u1, double u2) {
    const double phi = 2.0 * std::numbers::pi * u2;
    return cosine_hemisphere(u1, std::cos(phi), std::sin(phi));
}

}  // namespace brdfz
