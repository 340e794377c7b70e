// The virtual gonioreflectometer: evaluate any Brdf at the sample positions of a Rusinkiewicz grid.
// Bins whose wi or wo falls below the horizon are marked invalid (MERL leaves them unmeasured too).
// Sources are taken as isotropic: bins are evaluated at φh = 0. On a reciprocal grid (table.h) a bin
// holds the pair (wi, wo) and its exchange (wo, wi): the mean of f at the two, unless the source is
// reciprocal (Brdf::reciprocal) and one evaluation gives both. On a bilateral grid likewise the pair
// and its mirror image (y → −y: φd → −φd), unless the source is mirror-symmetric (Brdf::bilateral);
// the exchange is not averaged in, so non-reciprocal data are kept.
// A source with a measured range (measured_theta_max() < π/2, brdf.h) is evaluated with the incident
// elevation clamped to that range and the outgoing one to max(range, outgoing_theta_max_deg), azimuths
// kept: constant extrapolation, continuous at the edge of the data, where the source's own
// extrapolation can be orders of magnitude off (RGL files beyond their last θi), and where measured
// radiance over a vanishing cosθo makes f noise (RGL files at θo → 90°: 10^5 against 10^2).
#pragma once

#include <array>
#include <functional>

#include "brdfz/brdf.h"
#include "brdfz/table.h"

namespace brdfz {

// What to do with negative values a source returns (measurement noise in real data).
enum class NegativePolicy {
    Clamp,       // store 0 and count it in ValidityCounts::clamped
    Invalidate,  // mark the channel invalid and count it in ValidityCounts::negative
};

struct TabulateOptions {
    GridSpec grid{};
    NegativePolicy negative = NegativePolicy::Clamp;
    // Box filter: with supersample = {a, b, c} a bin's value is the mean of the valid values at a·b·c
    // points spread evenly over it (the centres of its a×b×c equal sub-bins along the square-root θh,
    // θd and φd axes) instead of the value at its sample point; {1, 1, 1} point-samples. Needs bin
    // centres. One φd bin with c = 180 averages over φd: a bivariate (θh, θd) table.
    std::array<int, 3> supersample{1, 1, 1};
    // What a supersampled bin's value is made of its points: their mean (Box), or the values whose
    // linear lookup (TabularBrdf, Lookup::Linear) fits all the points best in the metrics' weighting,
    // least squares of f·cosθi (LeastSquares): interpolation then errs less between samples than with
    // point or box samples, which matters on coarse grids. LeastSquares keeps point sampling's valid
    // bins (below the horizon: invalid), clamps negative results to 0 (counted in `clamped`), and takes
    // at most 2^21 points (ValueError beyond).
    enum class Filter { Box, LeastSquares } filter = Filter::Box;
    // LeastSquares (and factored.h's fit=lsq, which takes its points from here): how the points weigh.
    // Bins: each point once (the fine grid's bins), the metrics over the grid; the square-root θh axis
    // crowds them near specular half vectors. SolidAngle: each by the solid angle of the pairs it stands
    // for (dωi dωo = 4 cosθd sinθd sinθh dθh dθd dφh dφd), the metrics over directions (metrics.h).
    enum class FitWeight { Bins, SolidAngle } fit_weight = FitWeight::Bins;
    // Box filter: points with θi or θo above this angle are left out of a bin's mean unless the bin has
    // no other valid point. LeastSquares: such points, and points evaluated at a clamped incident
    // elevation (beyond the source's measured_theta_max()), weigh a tenth in the fit. Grazing values are the least reliable (extrapolated in RGL files) and can be
    // orders of magnitude larger than the rest (10^5 against 0.3 in RGL's paper_white), so they would
    // dominate the mean. 90: no cut.
    double box_max_theta_deg = 80.0;
    // Sources with a measured range: outgoing elevations above max(this, measured_theta_max()) are
    // evaluated at it (see the top of this file).
    double outgoing_theta_max_deg = 80.0;
    int threads = 0;  // 0: one per hardware thread
    // Called with the fraction done (0..1] after each θh slice, from a worker thread under a lock.
    std::function<void(double)> progress;
};

// With supersampling, counts.valid counts bins that got a value, the other classes count points.
struct Tabulated {
    Table table;
    ValidityCounts counts;
    // Bins (points, when supersampled) above the horizon evaluated at a clamped elevation (see the top of
    // this file; on a reciprocal grid of a non-reciprocal source, in either of the two evaluations), not
    // in counts, whose classes the container stores.
    std::size_t extrapolated = 0;
};

Tabulated tabulate(const Brdf& brdf, const TabulateOptions& options = {});

}  // namespace brdfz
