// The table kernels (table_kernels.h) compiled for each Highway target: foreach_target.h includes this
// file again for each, and lib/runtime/src/hwy_dispatch.h picks one at run time. Without FMA
// contraction (brdfz_float), so every target gives the same bits as the one-pair calls and
// brdfz::runtime.
#ifndef BRDFZ_REPR_TABLE_KERNELS_ONCE
#define BRDFZ_REPR_TABLE_KERNELS_ONCE
#include "repr/table_kernels.h"

#include "hwy_dispatch.h"
#include "detail/simd.h"
#include "detail/table_lookup.h"
#include "detail/table_sample.h"
#endif  // BRDFZ_REPR_TABLE_KERNELS_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "repr/table_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "blend_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::detail::HWY_NAMESPACE {

// The corners' blend across channels, as brdfz::runtime's build for the target blends them.
using Blend = runtime::kernels::HWY_NAMESPACE::BlendLanes;

// Each kernel whole for the target (flatten: its loops vectorise only where nothing in them is a call).
template <typename Values>
[[gnu::flatten]] Rgb EvalOne(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi, const Vec3& wo) {
    return eval_one<Blend>(g, values, lookup, wi, wo);
}
template <typename Values>
[[gnu::flatten]] void EvalBatch(const GridSpec& g, const Values& values, Lookup lookup, const Vec3* wi, const Vec3* wo,
                                Rgb* out, std::size_t n) {
    eval_table_passes<Blend>(g, values, lookup, wi, wo, out, n);
}
template <typename Values>
[[gnu::flatten]] BrdfSample SampleOne(const GridSpec& g, const Values& values, Lookup lookup,
                                      const HalfVectorSampler& sampler, const Vec3& wo, double u1, double u2) {
    return sample_one<Blend>(g, values, lookup, sampler, wo, u1, u2);
}
template <typename Values>
[[gnu::flatten]] void SampleBatch(const GridSpec& g, const Values& values, Lookup lookup,
                                  const HalfVectorSampler& sampler, const Vec3* wo, const std::array<double, 2>* u,
                                  BrdfSample* out, std::size_t n) {
    sample_table_passes<Blend>(g, values, lookup, sampler, wo, u, out, n);
}

}  // namespace brdfz::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace brdfz::detail {

template <typename Values>
Rgb eval_table(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi, const Vec3& wo) {
    static const auto builds = BRDFZ_HWY_BUILDS(EvalOne<Values>);
    return builds.at(simd_level())(g, values, lookup, wi, wo);
}

template <typename Values>
void eval_table_batch(const GridSpec& g, const Values& values, Lookup lookup, const Vec3* wi, const Vec3* wo,
                      Rgb* out, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(EvalBatch<Values>);
    builds.at(simd_level())(g, values, lookup, wi, wo, out, n);
}

template <typename Values>
BrdfSample sample_table(const GridSpec& g, const Values& values, Lookup lookup, const HalfVectorSampler& sampler,
                        const Vec3& wo, double u1, double u2) {
    static const auto builds = BRDFZ_HWY_BUILDS(SampleOne<Values>);
    return builds.at(simd_level())(g, values, lookup, sampler, wo, u1, u2);
}

template <typename Values>
void sample_table_batch(const GridSpec& g, const Values& values, Lookup lookup, const HalfVectorSampler& sampler,
                        const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(SampleBatch<Values>);
    builds.at(simd_level())(g, values, lookup, sampler, wo, u, out, n);
}

#define BRDFZ_TABLE_KERNELS(Values)                                                                              \
    template Rgb eval_table(const GridSpec&, const Values&, Lookup, const Vec3&, const Vec3&);                 \
    template void eval_table_batch(const GridSpec&, const Values&, Lookup, const Vec3*, const Vec3*, Rgb*,     \
                                   std::size_t);                                                              \
    template BrdfSample sample_table(const GridSpec&, const Values&, Lookup, const HalfVectorSampler&,         \
                                     const Vec3&, double, double);                                            \
    template void sample_table_batch(const GridSpec&, const Values&, Lookup, const HalfVectorSampler&,         \
                                     const Vec3*, const std::array<double, 2>*, BrdfSample*, std::size_t);
BRDFZ_TABLE_KERNELS(TableFloat32Values)
BRDFZ_TABLE_KERNELS(HalfValues)
BRDFZ_TABLE_KERNELS(LogU8Values)
#undef BRDFZ_TABLE_KERNELS

}  // namespace brdfz::detail
#endif  // HWY_ONCE
