// compress(): build any compact representation of a Brdf from its ReprSpec text — the one entry
// point behind `brdfz compress`, Python's brdfz.compress and the budget-driven selection.
//
// Kinds (each documented with its options in its own header under repr/):
//   tabular:res=AxBxC,dtype=f32|f16|u8log[,lookup=linear|nearest,ss=N,filter=box|lsq,dwarp=W]
//                                           resampled Rusinkiewicz table (repr/tabular.h, compact_table.h),
//                                           each bin the mean of N³ points (default 1: point samples), or
//                                           with filter=lsq the least-squares fit of the linear lookup to
//                                           them (tabulate.h; default N = 3); dwarp=W in [0, 0.95]: θd
//                                           axis warped towards grazing (table.h; default 0, linear)
//   bivariate:res=AxB,dtype=...[,lookup=...,ss=N,phi=P,filter=box|lsq,dwarp=W]   (θh, θd) table, the source
//                                           averaged over P φd values (default 180) and N² points per bin
//                                           (default 1), or fitted to them (filter=lsq)
//   analytic:MODEL[,loss=log|cos|cbrt,starts=N,seed=S]   a Ceres fit (fit/fit.h)
//   pca:basis=FILE,k=K[,store=reference|embed,lookup=linear|nearest]   k coefficients of a shared
//                                                   basis read from FILE (repr/pca.h)
//   svd:rank=K,space=linear|cos|log|cbrt,layout=h_dp|hd_p,colour=separate|shared[,res=AxBxC,iterations=N,dwarp=W,
//       fit=samples|lsq,ss=N,fit_iterations=N,dtype=f32|f16]
//   nmf:(the same keys)                     low-rank / non-negative factorisation (repr/factored.h);
//                                           dwarp=W (with res=): the res grid's θd axis warped as for tables;
//                                           fit=lsq (with res=): the factors refitted through eval's
//                                           interpolation to N³ points per bin (ss=N, default 2), as
//                                           filter=lsq fits tables; dtype=f16: float16 factors (half the bytes)
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/measurements.h"
#include "brdfz/repr/spec.h"

namespace brdfz {

struct CompressOptions {
    int threads = 0;  // 0: one per hardware thread
    // Fraction done (0..1]; may be called from worker threads, under a lock.
    std::function<void(double)> progress;
};

struct Compressed {
    std::unique_ptr<Brdf> brdf;
    std::string spec;               // canonical spec text (ReprSpec::str())
    double build_seconds = 0;       // wall time of compress()
    std::vector<std::string> notes; // what the builder wants the user to know (fit status, clamping)
};

// ValueError for an unknown kind or a bad option (naming it); the builders' own errors pass through.
Compressed compress(const Brdf& source, const std::string& spec, const CompressOptions& options = {});

// Scattered measurements (Cornell, ALTA) have no grid to factor or resample: only `analytic` fits
// them; ValueError for any other kind.
Compressed compress(const MeasurementSet& source, const std::string& spec, const CompressOptions& options = {});

// The kinds compress() knows, for help texts.
std::vector<std::string> compress_kinds();

}  // namespace brdfz
