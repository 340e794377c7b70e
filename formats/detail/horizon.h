// The horizon test readers of scattered measurements share: a direction whose polar angle is within
// 1e-9 rad of π/2 or beyond (z <= sin 1e-9) is on or below the horizon. Grazing samples measured at
// exactly 90° would otherwise be kept or dropped by the rounding of cos(π/2).
#pragma once

#include "brdfz/frame.h"

namespace brdfz::detail {

inline constexpr double kHorizonZ = 1e-9;

inline bool above_horizon(const Vec3& w) { return w.z > kHorizonZ; }

}  // namespace brdfz::detail
