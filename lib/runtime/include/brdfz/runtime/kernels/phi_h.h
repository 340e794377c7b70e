// A φh stack's interpolation (the core's PhiHBrdf, brdfz/repr/phi_h.h): which two slices a pair reads,
// with what weight, and whether it reads them mirrored. Slice k of n sits at φk = (k + ½)·range/n, the
// range 2π, or π for the mirror fold, where a pair with φh < 0 is read mirrored (y → −y).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::runtime::kernels {

struct PhiHPick {
    std::size_t k0, k1;
    double t;       // weight of k1
    bool mirrored;  // read both directions with y → −y
    bool ok;        // false where φh is not finite (the value is then 0)
};

inline PhiHPick phi_h_pick(bool bilateral, std::size_t n, const Vec3& wi, const Vec3& wo) {
    const Vec3 h{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    double phi = std::atan2(h.y, h.x);  // (−π, π]; 0 at the normal, where every slice agrees
    if (!std::isfinite(phi)) return {0, 0, 0.0, false, false};
    const double nd = static_cast<double>(n);
    if (bilateral) {
        const bool mirrored = phi < 0.0;
        if (mirrored) phi = -phi;
        const double u = std::fmin(std::fmax(phi / kPi * nd - 0.5, 0.0), nd - 1.0);
        const std::size_t k0 = std::min(static_cast<std::size_t>(u), n - 2);
        return {k0, k0 + 1, u - static_cast<double>(k0), mirrored, true};
    }
    if (phi < 0.0) phi += 2.0 * kPi;
    double u = phi / (2.0 * kPi) * nd - 0.5;  // in [−0.5, n − 0.5]
    if (u < 0.0) u += nd;
    const std::size_t i = std::min(static_cast<std::size_t>(u), n - 1);
    return {i, (i + 1) % n, std::fmin(std::fmax(u - static_cast<double>(i), 0.0), 1.0), false, true};
}

}  // namespace brdfz::runtime::kernels
