// Local-frame helpers shared by every representation (the vector type and elevation() are the runtime's,
// brdfz/runtime/vec.h, as is the cosine-weighted direction).
//
// The local shading frame has the surface normal on +z; see brdf.h for the full conventions.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/runtime/kernels/lobes/sampling.h"
#include "brdfz/runtime/vec.h"

namespace brdfz {

// Spherical direction with polar angle theta from +z and azimuth phi from +x.
inline Vec3 spherical_direction(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// Cosine-weighted direction on the upper hemisphere (pdf cosθ/π) by Malley's method, from cos φ and
// sin φ (the lobe samplers', brdfz/runtime/kernels/lobes/sampling.h) ...
using lobes::sampling::cosine_hemisphere;

// ... or from u1, u2 in [0, 1), azimuth 2π·u2.
inline Vec3 cosine_hemisphere(double u1, double u2) {
    const double phi = 2.0 * std::numbers::pi * u2;
    return cosine_hemisphere(u1, std::cos(phi), std::sin(phi));
}

}  // namespace brdfz
