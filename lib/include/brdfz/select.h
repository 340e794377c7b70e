// Choosing a representation: try candidates, measure what each achieves, keep the smallest that is
// good enough. trial() is the measurement behind `brdfz compress`, the compression benchmark and the
// budget-driven selection alike, so all three report the same numbers.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/metrics.h"
#include "brdfz/scene.h"

namespace brdfz {

struct TrialOptions {
    CompressOptions compress;
    MetricOptions metrics;
    bool measure_speed = true;  // eval_rate() of the result (a short timed batch)
};

// What one representation achieved against its source (zfp-style: measured, not asked for).
struct Trial {
    std::string spec;               // canonical spec text
    std::string describe;           // the result's describe()
    std::size_t bytes = 0;          // Brdf::nbytes() of the result
    Metrics metrics;                // the result against the source
    double eval_rate = 0;           // batch eval, pairs per second on one thread (0: not measured)
    double build_seconds = 0;
    std::vector<std::string> notes; // from the builder (fit status, clamping)
    std::unique_ptr<Brdf> brdf;
};

// compress(source, spec) and measure it. Errors of compress() pass through.
Trial trial(const Brdf& source, const std::string& spec, const TrialOptions& options = {});
Trial trial(const MeasurementSet& source, const std::string& spec, const TrialOptions& options = {});

// Budget-driven selection, by an error budget, a size budget or both:
//   max_error alone: the smallest candidate whose error meets it;
//   max_bytes alone: the most accurate candidate of at most that many bytes (the first of equal error);
//   both:            the smallest candidate within both.
//
// The error of a candidate, by metric:
//   without a scene: cos = cos_rmse_rel (mean of channels), log = log_rmse, image = scene_error on
//                    default_scene();
//   with a scene:    scene_error(metric) under that scene (scene.h).
// Candidates are tried in the order given — cheapest (fewest bytes) first — and the search stops at
// the first that meets an error budget, or at the first larger than the size budget, so the order must
// be by size; default_candidates() is.
struct SelectOptions {
    std::optional<double> max_error = 0.05;
    std::optional<std::uint64_t> max_bytes;
    SceneMetric metric = SceneMetric::Log;
    std::optional<Scene> scene;
    std::vector<std::string> candidates;  // empty: default_candidates(source, trial.metrics)
    TrialOptions trial;
    // Called after each candidate (the CLI's progress lines).
    std::function<void(const struct Candidate&)> on_candidate;
};

struct Candidate {
    Trial trial;           // spec, bytes, metrics, speed, build time (no brdf unless chosen)
    double error = 0;      // by SelectOptions::metric, NaN when the candidate failed
    bool accepted = false;
    std::string reason;    // why it was rejected (or "meets the budget")
};

struct Selection {
    std::vector<Candidate> tried;
    int chosen = -1;  // index into tried; -1 when no candidate met the budget
    const Candidate* best() const { return chosen < 0 ? nullptr : &tried[static_cast<std::size_t>(chosen)]; }
};

// The settings the compression benchmark sweeps (bench/compress_sweep, python -m brdfz.bench): every
// kind at a few sizes, the float32 MERL-resolution table first as the baseline. Only registered kinds:
// the analytic fits where the program links brdfz::fit.
std::vector<std::string> benchmark_specs();

// The benchmark's CSV (bench/compress_sweep, `brdfz demo`; python -m brdfz.bench writes and reads the
// same columns): one row per material and setting. A setting that failed has empty numbers and the
// status "error: MESSAGE"; otherwise the status is "ok" followed by the builder's notes.
inline constexpr const char* kSweepCsvHeader =
    "material,format,repr,describe,bytes,input_bytes,ratio,cos_rmse,cos_rmse_rel,log_rmse,cbrt_rmse,"
    "eval_pairs_per_s,build_s,status";
// A line of it (no newline): `trial` measured, or `error` when trial is null.
std::string sweep_csv_row(const std::string& material, const std::string& format, const std::string& spec,
                          std::uintmax_t input_bytes, const Trial* trial, const std::string& error = {});
// The columns that follow the status when the errors over direction pairs are measured too (`brdfz demo`;
// python -m brdfz.bench's DIRECTIONS_COLUMNS), and their cells, each after a comma: empty without `over_directions`.
inline constexpr const char* kSweepCsvDirectionsColumns =
    "directions_cos_rmse,directions_cos_rmse_rel,directions_log_rmse,directions_cbrt_rmse";
std::string sweep_csv_directions(const Metrics* over_directions);

// Candidates from cheapest to richest: analytic fits of growing lobe count, factorisations of growing
// rank, compact tables, the full-resolution table. Only registered kinds, as benchmark_specs().
std::vector<std::string> default_candidates();

// The reciprocity error (reciprocity_error()'s cos_rmse_rel.mean, what `brdfz info` prints) above which a
// source is not reciprocal to the default candidates and the benchmark's quick settings, which then keep
// φd whole (keep_phi_d_whole()). Reciprocal sources measure about 0 (a table on a reciprocal grid exactly
// 0, analytic models to rounding), the shared RGL files 0.1-1. A reciprocal fold stores the mean of
// f(wi, wo) and f(wo, wi), off by about half the reciprocity error: at 1 % a quarter of the benchmark's
// smallest budget (2 %), far below what real measurements show.
inline constexpr double kReciprocityThreshold = 0.01;

// Whether `source`'s reciprocity error, measured with `options` (directions, seed, max_theta_deg, threads;
// over is not used), is at most kReciprocityThreshold.
bool is_reciprocal(const Brdf& source, const MetricOptions& options = {});

// `specs` with φd kept whole: each whose kind takes symmetry=bilateral (tabular, svd, nmf) and that folds
// φd by reciprocity (symmetry=reciprocal, or no symmetry) gets symmetry=bilateral, as many bins with
// f(wi, wo) and f(wo, wi) apart (folded by the mirror that isotropic data have); the others (analytic
// fits, bivariate tables without a φd axis, symmetry=none or bilateral already) as given. Bytes do not
// change, so a list by size stays one.
std::vector<std::string> keep_phi_d_whole(std::vector<std::string> specs);

// default_candidates() for `source`: keep_phi_d_whole() of them when it is not reciprocal (is_reciprocal()
// with `options`).
std::vector<std::string> default_candidates(const Brdf& source, const MetricOptions& options = {});

// ValueError for no budget, an error budget that is not finite and > 0, a size budget of 0, or an
// empty candidate list; SpecError for a
// misspelt candidate: before anything is built when check_spec() finds it (an unknown kind or key),
// else when its builder refuses a value. A candidate that fails to build otherwise is rejected with
// its error message as the reason, not thrown.
Selection select_representation(const Brdf& source, const SelectOptions& options);

}  // namespace brdfz
