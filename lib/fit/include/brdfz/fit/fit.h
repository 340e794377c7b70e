// Fitting analytic models (repr/analytic/model.h) to measured data with Ceres.
//
// The objective is a sum over samples and channels of squared residuals r = L(f_model·cosθi) −
// L(f_data·cosθi), with the loss transform L one of
//   Cosine  L(x) = x          cosine-weighted L2 (Ngan et al. 2005)
//   Log     L(x) = ln(1 + x)  (Löw et al. 2012), the default: specular peaks do not dominate
//   Cbrt    L(x) = ∛x
// optionally wrapped in a robust loss. Samples with θi or θo at or above the cut-off (80° by
// default) and samples without a finite value are left out.
//
// Search: N starts — the model's defaults, then values drawn from a generator seeded by `seed`
// (log-uniform for roughness-like parameters), each with its colour weights scaled to the data —
// are each fitted on a fixed subset of the samples; the best is refined on all of them. Parameters
// stay inside their bounds (Levenberg-Marquardt with box constraints); roughness-like parameters are
// optimised as logarithms.
//
// Every fit returns a model with finite parameters inside their bounds and a report whose status
// says whether to trust it: converged, hit_bounds (a non-trivial bound is active: the data asks for
// more than the model allows, e.g. a mirror below the smallest roughness), no_convergence (iteration
// or time limit, or solver failure: the best parameters found are returned), insufficient_data (too
// few usable samples, or all zero: the defaults are returned). Beside the status, `poor_fit` says
// whether the model describes the data at all: a fit can converge, inside its bounds, to a model that
// misses most of the data (a Blinn-Phong lobe on a Fresnel-weighted highlight). See docs/fitting.md.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/fit/samples.h"
#include "brdfz/measurements.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/model.h"

namespace brdfz {

enum class FitLoss { Cosine, Log, Cbrt };
enum class RobustLoss { None, Huber, Cauchy };
enum class FitStatus { Converged, HitBounds, NoConvergence, InsufficientData };

FitLoss parse_fit_loss(const std::string& name);  // "cos" | "log" | "cbrt"; ValueError otherwise
const char* fit_loss_name(FitLoss loss);
RobustLoss parse_robust_loss(const std::string& name);  // "none" | "huber" | "cauchy"
const char* robust_loss_name(RobustLoss loss);
const char* fit_status_name(FitStatus status);  // "converged", "hit_bounds", ...

struct FitOptions {
    FitLoss loss = FitLoss::Log;
    double max_theta_deg = 80.0;
    int starts = 8;             // 1..kMaxStarts
    static constexpr int kMaxStarts = 1000;  // as analytic:MODEL,starts=N: each start is a solve
    std::uint64_t seed = 1;
    RobustLoss robust = RobustLoss::None;
    double robust_scale = 0.1;  // residual (in loss units) beyond which the robust loss flattens
    int threads = 0;            // 0: one per hardware thread
    int start_iterations = 25;  // per start: enough to rank them, not to finish
    int max_iterations = 100;   // of the refinement of the best start
    double max_seconds = 60.0;  // wall-clock bound of the whole fit
    // Samples each start is fitted on before the best one is refined on all of them.
    std::size_t coarse_samples = 3000;
    // The first start; empty: the model's defaults. Must fit the model (ValueError otherwise).
    std::vector<double> initial;
    // How a Brdf becomes samples (fit(const Brdf&, ...)); its cut-off is taken from max_theta_deg.
    SampleOptions sampling{GridSpec{90, 90, 180, BinPosition::Centre}, 90.0, 20000, 1, 0};
    // Grid of the metrics against a Brdf input; the cut-off is taken from max_theta_deg.
    MetricOptions metrics;
    // Fraction done (0..1], called from the fitting thread(s) under a lock.
    std::function<void(double)> progress;
};

struct FitReport {
    FitStatus status = FitStatus::InsufficientData;
    std::string message;                // one line: why this status
    std::vector<std::string> warnings;  // anything else worth knowing (poor fit, negative data)
    std::vector<std::string> at_bounds; // parameters that ended on a bound that is not a natural value
    std::string model;
    FitLoss loss = FitLoss::Log;
    std::size_t samples = 0;            // used by the fit
    std::size_t excluded_cutoff = 0;    // left out by the angular cut-off
    std::size_t excluded_invalid = 0;   // left out for lack of a finite value
    // A Brdf input: grid bins inside the cut-off before subsampling (the cut-off applies to the grid).
    std::size_t grid_bins = 0;
    std::array<double, 3> channel_cost{};  // ½ Σ r² per channel at the solution (Ceres' convention)
    double initial_cost = 0, final_cost = 0;  // of the refinement (all samples), robust loss included
    int iterations = 0;                 // of the kept start, both phases
    int total_iterations = 0;           // of every solve
    std::string termination;            // Ceres' termination type of the last solve, e.g. "CONVERGENCE"
    double seconds = 0;                 // wall time of the whole fit, sampling and metrics included
    int starts = 0, best_start = -1;
    std::vector<double> start_costs;    // each start's cost on the coarse subset (NaN if it failed)
    // Fraction of the data's variation, in the loss's space, the model leaves unexplained:
    // Σ r² / Σ (t − t̄)² over samples and channels (t the transformed data). 0 is a perfect fit.
    double unexplained = 0;
    std::optional<Metrics> metrics;     // the fitted model against the input (metrics.h)
    // Whatever the status, the model misses the data: unexplained > kPoorFitUnexplained, or the
    // metrics' cos_rmse_rel (mean of channels) > kPoorFitCosRmseRel. A warning says which.
    bool poor_fit = false;
    static constexpr double kPoorFitUnexplained = 0.25;
    // The log loss may follow the shape of a highlight and still miss its energy (a small
    // `unexplained`, a large cosine-weighted error), hence the second test.
    static constexpr double kPoorFitCosRmseRel = 0.5;
};

struct FitResult {
    AnalyticBrdf model;
    FitReport report;
};

// Fits `model` (a model string, model.h) to scattered samples; their monochrome/RGB nature is kept
// (a monochrome set fits the same value in all three channels). ValueError for a bad model string
// or options; data problems are reported in the status, not thrown.
FitResult fit(const MeasurementSet& data, const std::string& model, const FitOptions& options = {});

// Fits to any Brdf through sample_brdf (options.sampling), with metrics against the Brdf itself.
FitResult fit(const Brdf& source, const std::string& model, const FitOptions& options = {});

}  // namespace brdfz
