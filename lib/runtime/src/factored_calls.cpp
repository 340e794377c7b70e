#include "factored_calls.h"

namespace brdfz::runtime::detail {
namespace {

struct FactoredEval {
    static constexpr bool kAvx512 = true, kFma = true;  // the core's kernel's builds
    template <Simd S>
    static void run(const kernels::FactorView& f, const Vec3& wi, const Vec3& wo, double* out) {
        kernels::eval_factored<static_cast<int>(kernels::factor_lanes(S))>(f, wi, wo, out);
    }
};

}  // namespace

FactoredEvalFn* factored_eval_build(Simd level) {
    return kernels::Builds<FactoredEval, void(const kernels::FactorView&, const Vec3&, const Vec3&, double*)>::at(level);
}

}  // namespace brdfz::runtime::detail
