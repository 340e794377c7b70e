// Small vector type and local-frame helpers shared by every representation.
//
// The local shading frame has the surface normal on +z; see brdf.h for the full conventions.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

namespace brdfz {

struct Vec3 {
    double x = 0, y = 0, z = 0;
};

inline constexpr Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline constexpr Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline constexpr Vec3 operator*(double s, const Vec3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) { return (1.0 / length(a)) * a; }

// Spherical direction with polar angle theta from +z and azimuth phi from +x.
inline Vec3 spherical_direction(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// Cosine-weighted direction on the upper hemisphere (pdf cosθ/π) from u1, u2 in [0, 1), by Malley's
// method: a uniform point on the unit disk (radius √u1, azimuth 2π·u2) lifted to the hemisphere.
inline Vec3 cosine_hemisphere(double u1, double u2) {
    const double r = std::sqrt(u1), phi = 2.0 * std::numbers::pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::fmax(0.0, 1.0 - u1))};
}

// asin clamped to its domain, so unit vectors that are a rounding error too long stay finite.
inline double safe_asin(double x) { return std::asin(std::clamp(x, -1.0, 1.0)); }

// Polar angle of a (near-)unit vector. 2·asin(½‖v − ẑ‖) is well conditioned near the pole where
// acos(z) loses half the digits; the mirrored form covers the lower hemisphere.
inline double elevation(const Vec3& v) {
    const double dz = v.z >= 0 ? v.z - 1.0 : v.z + 1.0;
    const double half_chord = 0.5 * std::sqrt(v.x * v.x + v.y * v.y + dz * dz);
    const double t = 2.0 * safe_asin(half_chord);
    return v.z >= 0 ? t : std::numbers::pi - t;
}

}  // namespace brdfz
