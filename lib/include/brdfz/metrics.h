// Error metrics between two BRDFs, over the bins of a grid or over direction pairs.
//
// Over the grid (MetricOptions::over = Over::Grid, the default): samples are the bins of the
// reference's own grid when it stores a table (its invalid bins are skipped; an approximation storing
// a table on the same grid is read at its stored values too, so a table against itself is exactly 0),
// otherwise of MetricOptions::grid; bins with θi or θo >= max_theta_deg, or beyond the reference's
// measured_theta_max() (extrapolated, brdf.h), are left out. Each bin counts once (the MERL
// literature's convention, e.g. Ngan et al. 2005, Löw et al. 2012), so the grid's square-root θh axis
// weights near-specular half vectors more than their solid angle, and a reciprocal grid's φd ∈ [0, π)
// sees each pair on one side only.
//
// Over directions (Over::Directions; what a renderer asks for): `directions` pairs (wi, wo), wi and wo
// independent and uniform in solid angle, wi over θi < min(max_theta_deg, measured_theta_max()) and wo
// over θo < max_theta_deg, every azimuth; pair k is a function of (k, seed) only (direction_pairs()),
// so results do not depend on the thread count. Each pair counts once: the means below are Monte Carlo
// estimates of averages over that product of solid angles, whatever either BRDF's parameterisation.
//
// With x = max(f_ref, 0)·cosθi and y = max(f_approx, 0)·cosθi per channel at each sample (negative
// values, noise in some measurements, enter as 0 and are counted):
//   cos_rmse     = sqrt(mean (x − y)²)
//   cos_rmse_rel = sqrt(Σ (x − y)² / Σ x²)
//   log_rmse     = sqrt(mean (ln(1 + x) − ln(1 + y))²)
//   cbrt_rmse    = sqrt(mean (∛x − ∛y)²)
// `mean` is the average of the three channel values. A sample where either value is not finite is
// left out. ValueError when no sample is inside the cut-off, or when the reference is zero or negative
// at every one (no scale for cos_rmse_rel).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

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

// Where the metrics are taken (see the top of this file).
enum class Over { Grid, Directions };
Over parse_over(const std::string& name);  // "grid" | "directions"; ValueError otherwise
const char* over_name(Over over);

struct MetricOptions {
    // Sample grid when the reference is not a table. Bin starts, so that a table approximating an
    // analytic reference on the default (bin-centre) grid is judged between its samples, not at them.
    GridSpec grid{90, 90, 180, BinPosition::Start};
    double max_theta_deg = 80.0;
    int threads = 0;  // 0: one per hardware thread
    Over over = Over::Grid;
    std::size_t directions = std::size_t{1} << 18;  // pairs drawn over directions, in [1, kMaxDirections]
    std::uint64_t seed = 1;                          // of those pairs
    static constexpr std::size_t kMaxDirections = std::size_t{1} << 30;
};

Metrics compare(const Brdf& reference, const Brdf& approx, const MetricOptions& options = {});

// The samples compare() takes against `reference`: the pairs and the reference's values there (over the
// grid: the bins kept, in bin order, a table's stored values; over directions: direction_pairs()
// evaluated). For judging something that is not a Brdf (a peer's network) on the same samples with
// compare_values().
struct MetricSamples {
    std::vector<Vec3> wi, wo;
    std::vector<Rgb> reference;
};
MetricSamples metric_samples(const Brdf& reference, const MetricOptions& options = {});

// The metrics of approximate values against reference values at pairs whose incident directions are
// wi (cosθi = wi.z); the three spans of equal length (ValueError otherwise, or when none is finite).
Metrics compare_values(std::span<const Vec3> wi, std::span<const Rgb> reference, std::span<const Rgb> approx);

// Over::Directions' pairs, k = first .. first + wi.size() − 1: the k-th pair depends only on (k, seed)
// and the two cut-offs (radians, in (0, π/2]). ValueError for a cut-off outside that range or spans
// of unequal length.
void direction_pairs(std::uint64_t first, std::uint64_t seed, double theta_i_max, double theta_o_max,
                     std::span<Vec3> wi, std::span<Vec3> wo);

// The same metrics at the points of scattered measurements (Cornell, ALTA): every sample with θi
// and θo below max_theta_deg counts once, x being its measured f_r·cosθi. A monochrome set's value
// repeated in the three channels is compared with each of approx's channels. options.grid and
// options.threads are not used. ValueError when no sample lies inside the cut-off, and for
// Over::Directions (measurements are judged at their own points).
Metrics compare(const MeasurementSet& reference, const Brdf& approx, const MetricOptions& options = {});

// How far a BRDF is from reciprocal: the metrics of f(wo, wi) against f(wi, wo) over options.directions
// pairs uniform in solid angle (options.seed), both elevations below max_theta_deg and within the
// measured range (so that neither side is the BRDF's own extrapolation); options.over is not used.
// cos_rmse_rel.mean is "the reciprocity error" `brdfz info` and `validate` report: 0 for a table on a
// reciprocal grid, 0.1-1 for real RGL files at grazing angles.
Metrics reciprocity_error(const Brdf& brdf, const MetricOptions& options = {});

// Speed of batch eval on one thread, in direction pairs per second: the median of `reps` timed runs
// over the same `pairs` uniformly random hemisphere pairs (fixed seed), after one untimed warm-up.
double eval_rate(const Brdf& brdf, std::size_t pairs = std::size_t{1} << 16, int reps = 5);

}  // namespace brdfz
