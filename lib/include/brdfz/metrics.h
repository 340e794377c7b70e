// Error metrics between two BRDFs over the valid bins of a reference grid.
//
// Samples are the bins of the reference's own grid when it stores a table (its invalid bins are
// skipped; an approximation storing a table on the same grid is read at its stored values too, so a
// table against itself is exactly 0), otherwise of MetricOptions::grid; bins with θi or θo >=
// max_theta_deg, or beyond the reference's measured_theta_max() (extrapolated, brdf.h), are left out.
// Each bin counts once (the MERL literature's convention, e.g. Ngan et al. 2005, Löw et al. 2012).
// With x = max(f_ref, 0)·cosθi and y = max(f_approx, 0)·cosθi per channel (negative values, noise in
// some measurements, enter as 0 and are counted):
//   cos_rmse     = sqrt(mean (x − y)²)
//   cos_rmse_rel = sqrt(Σ (x − y)² / Σ x²)
//   log_rmse     = sqrt(mean (ln(1 + x) − ln(1 + y))²)
//   cbrt_rmse    = sqrt(mean (∛x − ∛y)²)
// `mean` is the average of the three channel values. ValueError when no sample is inside the
// cut-off, or when the reference is zero or negative at every one (no scale for cos_rmse_rel).
#pragma once

#include <cstddef>

#include "brdfz/brdf.h"
#include "brdfz/measurements.h"
#include "brdfz/table.h"

namespace brdfz {

struct PerChannel {
    double r = 0, g = 0, b = 0, mean = 0;
};

struct Metrics {
    PerChannel cos_rmse, cos_rmse_rel, log_rmse, cbrt_rmse;
    std::size_t samples = 0;    // bins compared
    std::size_t negatives = 0;  // channel values below 0 (either BRDF), taken as 0
};

struct MetricOptions {
    // Sample grid when the reference is not a table. Bin starts, so that a table approximating an
    // analytic reference on the default (bin-centre) grid is judged between its samples, not at them.
    GridSpec grid{90, 90, 180, BinPosition::Start};
    double max_theta_deg = 80.0;
    int threads = 0;  // 0: one per hardware thread
};

Metrics compare(const Brdf& reference, const Brdf& approx, const MetricOptions& options = {});

// The same metrics at the points of scattered measurements (Cornell, ALTA): every sample with θi
// and θo below max_theta_deg counts once, x being its measured f_r·cosθi. A monochrome set's value
// repeated in the three channels is compared with each of approx's channels. options.grid and
// options.threads are not used. ValueError when no sample lies inside the cut-off.
Metrics compare(const MeasurementSet& reference, const Brdf& approx, const MetricOptions& options = {});

// Speed of batch eval on one thread, in direction pairs per second: the median of `reps` timed runs
// over the same `pairs` uniformly random hemisphere pairs (fixed seed), after one untimed warm-up.
double eval_rate(const Brdf& brdf, std::size_t pairs = std::size_t{1} << 16, int reps = 5);

}  // namespace brdfz
