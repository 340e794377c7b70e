// The factored eval's builds (factored_calls.h), one per Highway target: foreach_target.h includes this
// file again for each, and hwy_dispatch.h picks one.
#ifndef BRDFZ_RUNTIME_FACTORED_CALLS_ONCE
#define BRDFZ_RUNTIME_FACTORED_CALLS_ONCE
#include "factored_calls.h"
#include "hwy_dispatch.h"
#endif  // BRDFZ_RUNTIME_FACTORED_CALLS_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "factored_calls.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "factor_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::runtime::detail::HWY_NAMESPACE {

// The target's sums, as the library's build of the kernel for the target.
[[gnu::flatten]] void FactoredEval(const kernels::FactorView& f, const Vec3& wi, const Vec3& wo, double* out) {
    kernels::eval_factored<kernels::HWY_NAMESPACE::FactorLanes>(f, wi, wo, out);
}

}  // namespace brdfz::runtime::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace brdfz::runtime::detail {

FactoredEvalFn* factored_eval_build(Simd level) {
    static const auto builds = BRDFZ_HWY_BUILDS(FactoredEval);
    return builds.at(level);
}

}  // namespace brdfz::runtime::detail
#endif  // HWY_ONCE
