// The virtual gonioreflectometer: evaluate any Brdf at the sample positions of a Rusinkiewicz grid.
// Bins whose wi or wo falls below the horizon are marked invalid (MERL leaves them unmeasured too).
// Sources are taken as isotropic: bins are evaluated at φh = 0.
#pragma once

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
    int threads = 0;  // 0: one per hardware thread
    // Called with the fraction done (0..1] after each θh slice, from a worker thread under a lock.
    std::function<void(double)> progress;
};

struct Tabulated {
    Table table;
    ValidityCounts counts;
};

Tabulated tabulate(const Brdf& brdf, const TabulateOptions& options = {});

}  // namespace brdfz
