// The Rusinkiewicz tables' kernels (TabularBrdf, CompactTableBrdf): eval and sample with its weight, one
// pair and in batches, for each of the library's Values policies. Their bodies are detail/table_lookup.h's
// and detail/table_sample.h's; table_kernels.cpp compiles them for each Highway target and runs the one
// for simd_level() (lib/runtime/src/hwy_dispatch.h).
#pragma once

#include <array>
#include <cstddef>

#include "brdfz/repr/tabular.h"
#include "brdfz/runtime/kernels/values.h"
#include "brdfz/sample/halfvector.h"
#include "brdfz/table.h"

namespace brdfz::detail {

// A Table's float32 values (the runtime's policy), readable as four floats a bin (Table pads its
// storage, so a corner loads as one vector: runtime/kernels/grid.h, FloatBins).
struct TableFloat32Values : runtime::kernels::Float32Values {
    const float* floats(std::size_t bin) const { return data + 3 * bin; }
};
using runtime::kernels::HalfValues;
using runtime::kernels::LogU8Values;

// Defined for TableFloat32Values, HalfValues and LogU8Values.
template <typename Values>
Rgb eval_table(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi, const Vec3& wo);
template <typename Values>
void eval_table_batch(const GridSpec& g, const Values& values, Lookup lookup, const Vec3* wi, const Vec3* wo,
                      Rgb* out, std::size_t n);
template <typename Values>
BrdfSample sample_table(const GridSpec& g, const Values& values, Lookup lookup, const HalfVectorSampler& sampler,
                        const Vec3& wo, double u1, double u2);
template <typename Values>
void sample_table_batch(const GridSpec& g, const Values& values, Lookup lookup, const HalfVectorSampler& sampler,
                        const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n);

}  // namespace brdfz::detail
