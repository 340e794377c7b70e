// The points of a least-squares fit through a grid's linear lookup, shared by tabulate.h's filter=lsq
// (bin values) and factored.h's fit=lsq (factor rows): the source's valid point samples at the centres
// of a grid `supersample` times finer (tabulate_points: elevations beyond the source's measured range
// taken at it), each with the scale of its row in the fit.
#pragma once

#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/tabulate.h"

namespace brdfz::detail {

struct FitPoints {
    std::vector<Vec3> wi, wo;   // above the horizon
    std::vector<Rgb> value;     // every channel valid
    // √(dθd/du) of the grid's θd axis relative to the linear one (1 on the linear axis), so that the sum
    // weighs θd uniformly as the metrics' linear grid does, times `outside_scale` for points with θi or
    // θo beyond options.box_max_theta_deg or the source's measured range. The metrics' cosθi is left to
    // the caller (wi.z).
    std::vector<double> scale;
};

inline constexpr std::size_t kMaxFitPoints = std::size_t{1} << 21;

// ValueError beyond kMaxFitPoints fine bins. options.supersample and options.grid as tabulate()'s (bin centres).
FitPoints fit_points(const Brdf& brdf, const TabulateOptions& options, double outside_scale);

}  // namespace brdfz::detail
