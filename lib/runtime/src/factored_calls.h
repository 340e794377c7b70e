// The factored eval's builds (kernels/factored.h), one per Highway target, with the sums of the core's
// kernel (lib/runtime/src/factor_lanes-inl.h), so that a material gives the library's bits at every
// level.
#pragma once

#include "brdfz/runtime/kernels/factored.h"

namespace brdfz::runtime::detail {

// f for a pair above the horizon.
using FactoredEvalFn = void(const kernels::FactorView&, const Vec3& wi, const Vec3& wo, double out[3]);

// The build for the level (its view's width a multiple of kernels::factor_lanes(level)).
FactoredEvalFn* factored_eval_build(Simd level);

}  // namespace brdfz::runtime::detail
