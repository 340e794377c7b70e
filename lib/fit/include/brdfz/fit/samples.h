// Turning any Brdf into a sample set for fitting: the valid bins of a (possibly subsampled)
// Rusinkiewicz grid, each with its direction pair and value.
#pragma once

#include <cstddef>
#include <cstdint>

#include "brdfz/brdf.h"
#include "brdfz/measurements.h"
#include "brdfz/table.h"

namespace brdfz {

struct SampleOptions {
    // Where sources that are not tables are evaluated; a TabularBrdf always gives its own bins.
    GridSpec grid{90, 90, 180, BinPosition::Centre};
    // Bins with θi or θo at or above this (degrees) are not sampled.
    double max_theta_deg = 90.0;
    // Keep a uniform random subset of about this many of the eligible bins (0: all of them). The
    // subset depends only on the grid, the seed and this number, never on the thread count.
    std::size_t max_samples = 0;
    std::uint64_t seed = 1;
    int threads = 0;  // 0: one per hardware thread
};

struct GridSamples {
    MeasurementSet set;
    std::size_t eligible = 0;  // bins above the horizon and inside the cut-off, before subsampling
    std::size_t invalid = 0;   // of the drawn bins, those without a finite value (unmeasured, NaN, Inf)
};

// The samples of `brdf`: a table's stored values at its bins' sample positions (invalid bins
// skipped), anything else evaluated at the bins of options.grid (non-finite values skipped).
// Directions follow brdf.h; isotropic sources, sampled at φh = 0 as tabulate() does.
GridSamples sample_brdf(const Brdf& brdf, const SampleOptions& options = {});

}  // namespace brdfz
