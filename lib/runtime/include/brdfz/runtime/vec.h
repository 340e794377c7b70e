// The direction type of brdfz and the geometry of a direction pair (the core's frame.h and coords.h
// build on it): three doubles in the local shading frame, normal +z (conventions: brdfz/brdf.h,
// formats/SPEC.md's runtime layout).
#pragma once

#include <algorithm>
#include <cmath>

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

// asin clamped to its domain, so unit vectors that are a rounding error too long stay finite.
inline double safe_asin(double x) { return std::asin(std::clamp(x, -1.0, 1.0)); }

// Polar angle of a (near-)unit vector. 2·asin(½‖v − ẑ‖) is well conditioned near the pole where
// acos(z) loses half the digits; the mirrored form covers the lower hemisphere.
inline double elevation(const Vec3& v) {
    constexpr double kPi = 3.141592653589793238462643383279502884;
    const double dz = v.z >= 0 ? v.z - 1.0 : v.z + 1.0;
    const double half_chord = 0.5 * std::sqrt(v.x * v.x + v.y * v.y + dz * dz);
    const double t = 2.0 * safe_asin(half_chord);
    return v.z >= 0 ? t : kPi - t;
}

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

// The direction a single-pair call uses for v (the library's Brdf and brdfz::runtime alike): v itself,
// or v normalised where its squared length is off 1 by more than 1e-14 (unit vectors computed in
// double are within 1e-15, so they pass unchanged; floats and hand-typed vectors are normalised);
// false for a NaN, infinite or zero v, whose call then gives 0.
inline bool prepare_direction(Vec3& v) {
    const double n2 = dot(v, v);
    if (!(n2 > 0.0 && n2 < 1e300)) return false;
    if (std::fabs(n2 - 1.0) > 1e-14) v = (1.0 / std::sqrt(n2)) * v;
    return true;
}

}  // namespace brdfz
