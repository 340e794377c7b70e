// FactoredBrdf: a Rusinkiewicz table stored as a low-rank product of two factor matrices.
//
// Each colour channel of a Table on a grid (nθh, nθd, nφd) is viewed as a matrix in one of two layouts,
//   HxDP:  rows θh,       columns (θd, φd)   — U [nθh, k],      V [nθd·nφd, k]
//   HDxP:  rows (θh, θd), columns φd         — U [nθh·nθd, k],  V [nφd, k]
// (in both, bin = row·columns + column: MERL's bin order), in a transform space
//   linear  y = f
//   cos     y = f, fitted with weights cos²θi, i.e. minimising the cosine-weighted error metrics.h
//           reports (f·cosθi in the least squares, without dividing by cosθi at eval time)
//   log     y = ln(1 + f)        (inverse expm1)
//   cbrt    y = ∛f               (inverse y³)
// and factored as y ≈ U·diag(s_c)·Vᵀ of rank k:
//   svd  unconstrained; reconstructions below 0 in the value domain are clamped to 0 and counted
//   nmf  U, V, s ≥ 0 (Lawrence et al. 2004), so reconstructions are ≥ 0 without clamping.
// Reconstructions above the factorised data's largest value (per channel, `max_value`) are clamped
// to it: where the data leave a bin unconstrained (invalid, or at the edge of the valid region) the
// product may extrapolate far beyond the data, and in log or cbrt space past the range of a double.
// Colour: `separate` factors each channel on its own (s_c = 1, three U and three V); `shared` uses
// one U and V for all channels and per-channel weights s_c per component (colour factored from
// intensity: a third of the storage).
//
// Invalid bins (any channel NaN, Inf or negative; below-horizon bins of tabulated sources) get weight
// 0: the factorisation is alternating weighted least squares (weighted non-negative least squares
// for nmf), so their values never influence the result, and the factors fill them in from the rest.
//
// Evaluation interpolates the factors linearly in the grid's bin coordinates (table.h's axis maps and
// bin position; φd periodic), multiplies and sums them: f(wi, wo) = T⁻¹(Σ_j Ũ_j·s_cj·Ṽ_j).
//
// Fit (fit=): by default the factors fit the table's values at its bins' sample positions (`samples`).
// With `lsq` they are then refitted by alternating weighted least squares THROUGH that interpolation
// (each point's design row is eval's own corner blend: 2 θh rows of U and 4 (θd, φd) rows of V in
// h_dp) to the source's values at the points of a grid `ss` times finer per axis, as tabulate.h's
// filter=lsq fits table bins: eval then errs less between the samples, where factors fitted to the
// samples alone leave the interpolation's error.
//
// Storage (dtype=): U and V as float32 or float16 (IEEE binary16: half the bytes, 2^-11 relative
// rounding; each component's columns scaled to a largest magnitude of 1 first, the scale moved into the
// colour weights, which stay float32). float16 factors are kept in memory as the floats they round to,
// so eval reads them as it reads float32 ones: nbytes() = 4 (float32) or 2 (float16) per U and V entry
// + 4 per colour weight, the bytes the container stores.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/sample/factor_sampler.h"
#include "brdfz/sample/grid_sampler.h"
#include "brdfz/simd.h"
#include "brdfz/table.h"
#include "brdfz/tabulate.h"

namespace brdfz {

enum class FactorMethod { Svd, Nmf };
enum class FactorSpace { Linear, Cos, Log, Cbrt };
enum class FactorLayout { HxDP, HDxP };
enum class FactorColour { Separate, Shared };
enum class FactorFit { Samples, LeastSquares };
enum class FactorDtype { F32, F16 };

// Names as the spec strings spell them ("svd", "log", "h_dp", "shared"); parse_* throw ValueError.
const char* factor_method_name(FactorMethod m);
const char* factor_space_name(FactorSpace s);
const char* factor_layout_name(FactorLayout l);
const char* factor_colour_name(FactorColour c);
const char* factor_fit_name(FactorFit f);      // "samples", "lsq"
const char* factor_dtype_name(FactorDtype d);  // "f32", "f16"
FactorMethod parse_factor_method(const std::string& name);
FactorSpace parse_factor_space(const std::string& name);
FactorLayout parse_factor_layout(const std::string& name);
FactorColour parse_factor_colour(const std::string& name);
FactorFit parse_factor_fit(const std::string& name);
FactorDtype parse_factor_dtype(const std::string& name);

// The stored parameters (what the container writes), row-major:
//   u       rows × m,  v  columns × m,   m = rank (shared) or 3·rank (separate: entry c·rank + j);
//           float32, or with dtype F16 floats that are float16 values (FactoredBrdf rounds them)
//   colour  3 × rank, the weights s_cj (shared; float32); empty for separate.
// max_value is the ceiling of eval per channel (factor() sets the data's maximum); +inf, as in
// containers written before it, leaves only the float range as a ceiling, so eval stays finite.
struct Factors {
    GridSpec grid{};
    FactorMethod method = FactorMethod::Svd;
    FactorSpace space = FactorSpace::Log;
    FactorLayout layout = FactorLayout::HxDP;
    FactorColour colour = FactorColour::Separate;
    int rank = 1;
    FactorDtype dtype = FactorDtype::F32;
    static constexpr float kUnbounded = std::numeric_limits<float>::infinity();
    std::vector<float> u, v, colour_weights;
    std::array<float, 3> max_value{kUnbounded, kUnbounded, kUnbounded};

    int rows() const;
    int columns() const;
    int row_width() const { return colour == FactorColour::Shared ? rank : 3 * rank; }  // m
};

class FactoredBrdf final : public Brdf {
public:
    // ValueError when the shapes disagree with the grid, layout and rank, a factor is not finite (for
    // F16: beyond the float16 range), the factors could reconstruct a value beyond a quarter of the
    // float range (the sum over components of the largest |u|·|v|), or a max_value is NaN or negative. F16 factors are rounded to
    // float16 (round to nearest even).
    // The sampler of that kind is built from eval (compact unless asked otherwise).
    explicit FactoredBrdf(Factors factors, SamplerKind sampler = SamplerKind::Compact);
    // With a stored compact sampler (a container's).
    FactoredBrdf(Factors factors, CompactSampler sampler);
    FactoredBrdf(const FactoredBrdf&) = delete;
    FactoredBrdf& operator=(const FactoredBrdf&) = delete;

    const Factors& factors() const { return f_; }
    // The reconstruction at every bin's sample position, in the value domain (negatives clamped):
    // what eval returns there. `clamped`, when given, receives the number of channel values clamped.
    Table reconstruct(std::size_t* clamped = nullptr) const;
    // Channel values eval has clamped to 0 so far (svd reconstructions below 0), over all threads.
    std::uint64_t clamped_evaluations() const { return clamped_.load(std::memory_order_relaxed); }

    // A sampler drawn from the factors alone (sample/factor_sampler.h; Lawrence et al. 2004), built
    // now, quick to build (no evaluation grid). Its azimuth follows cosθi only, so where f depends
    // strongly on φh (glossy paints at oblique views) its variance is well above the compact sampler's,
    // and its draws are slower: sample() does not use it.
    FactorSampler factor_sampler() const { return FactorSampler(f_); }
    // The sampler sample() and pdf() use (sample/grid_sampler.h), built with the representation.
    const GridSampler& sampler() const { return sampler_; }

    int channels() const override { return 3; }
    std::size_t nbytes() const override;
    std::string describe() const override;
    bool reciprocal() const override { return f_.grid.reciprocal(); }
    bool bilateral() const override { return f_.grid.bilateral(); }
    const GridSpec* grid() const override { return &f_.grid; }

protected:
    BRDFZ_BRDF_KERNELS;

private:
    Factors f_;
    // Evaluation copies (factored.cpp): U and V (u_, v_: in storage_, each from a cache line) with rows
    // zero-padded from m to width_ entries (whole SIMD steps of the kernel's build, simd_: the widest the
    // CPU has, chosen at construction; separate colour of rank 3 or 4 with each channel's components
    // from float 4c), and the colour mix, 3 × width_ in f_'s component order: the
    // colour weights, or for separate colour a one-hot selection of each channel's components.
    Simd simd_ = Simd::Sse2;
    std::size_t width_ = 0;
    std::vector<float> storage_, mix_;
    const float* u_ = nullptr;
    const float* v_ = nullptr;
    double ceiling_[3];  // max_value in the transform space (within the float range)
    mutable std::atomic<std::uint64_t> clamped_{0};
    GridSampler sampler_;
};

// Options of factor(). The spec-string kinds (compress.h) `svd:...` and `nmf:...` map onto these:
//   rank=K (default 4), space=linear|cos|log|cbrt (default log), layout=h_dp|hd_p (default h_dp),
//   colour=separate|shared (default separate), res=AxBxC (default: the source table's own grid, or
//   90x90x180 for a source that is not a table), iterations=N (default 50 svd, 100 nmf),
//   fit=samples|lsq (default samples; lsq needs res=), ss=N (fit=lsq: points per bin and axis,
//   default 2), fit_iterations=N (fit=lsq: the refit's cap, default 20), dtype=f32|f16 (default f32).
// Alternating least squares gains little after a few tens of iterations (gold-metallic-paint, rank 4,
// log: residual 0.00957 after 20 svd iterations, 0.00941 after 100), hence the caps and tolerance.
struct FactorOptions {
    FactorMethod method = FactorMethod::Svd;
    int rank = 4;
    FactorSpace space = FactorSpace::Log;
    FactorLayout layout = FactorLayout::HxDP;
    FactorColour colour = FactorColour::Separate;
    int max_iterations = 50;
    double tolerance = 1e-4;  // stop when an iteration lowers Σ w·(y − ŷ)² by less than this fraction
    FactorFit fit = FactorFit::Samples;
    int supersample = 2;      // fit=lsq: the fine grid's points per bin and axis
    int fit_iterations = 20;  // fit=lsq: the refit's cap (same tolerance)
    // fit=lsq: how its points weigh (tabulate.h): as the grid's bins, or by solid angle.
    TabulateOptions::FitWeight fit_weight = TabulateOptions::FitWeight::Bins;
    FactorDtype dtype = FactorDtype::F32;
    SamplerKind sampler = SamplerKind::Compact;  // the result's sampler (sample/grid_sampler.h)
    int threads = 0;          // 0: one per hardware thread
    // Fraction done (0..1] after each iteration, from the calling thread.
    std::function<void(double)> progress;
};

// What a factorisation achieved.
struct FactorReport {
    int iterations = 0;
    bool converged = false;     // the tolerance was met before the iteration cap
    double residual = 0;        // sqrt(Σ w·(y − ŷ)² / Σ w·y²) over the valid bins, in the transform space
    std::size_t valid_bins = 0; // bins that took part (weight > 0)
    std::size_t clamped = 0;    // reconstructed channel values at the grid's samples clamped to 0 (svd)
    // fit=lsq: the refit's iterations and sqrt(Σ w·(y − ŷ)² / Σ w·y²) over its points before (the
    // sample fit's factors) and after.
    int fit_iterations = 0;
    double fit_residual_start = 0, fit_residual = 0;
    std::size_t fit_points = 0;
};

struct Factored {
    std::unique_ptr<FactoredBrdf> brdf;
    FactorReport report;
};

// Factor a table's valid bins. ValueError for a rank outside [1, min(rows, columns)], a table without
// valid bins, a factorisation that produced non-finite values (diverged), or fit=lsq (it needs the
// source: the overload below).
Factored factor(const Table& table, const FactorOptions& options = {});

// The same, and with fit=lsq the refit through eval's interpolation to `source` at the points of
// `table`'s grid options.supersample times finer per axis (tabulate.h's filter=lsq points: elevations
// beyond the source's measured range taken at it, such points and those beyond 80° weighing a tenth;
// cos²θi weights in cos space). `table` is the source tabulated on the grid (the start, and its ceiling).
// ValueError beyond 2^21 points or 2^18 unknowns in one side's sparse normal equations.
Factored factor(const Brdf& source, const Table& table, const FactorOptions& options);

}  // namespace brdfz
