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

// half_frame, half_vector and difference_vector are the runtime's (brdfz/runtime/vec.h).

HalfDiff to_half_diff(const Vec3& wi, const Vec3& wo);

// {wi, wo} from half/difference angles.
std::pair<Vec3, Vec3> from_half_diff(const HalfDiff& hd);

}  // namespace brdfz
