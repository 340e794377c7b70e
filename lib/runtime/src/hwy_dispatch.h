// Which Highway build of a kernel runs at a level (brdfz/simd.h): the one place that maps brdfz's
// levels to Highway's targets. A kernel file compiles its body once per target (hwy/foreach_target.h,
// the targets the root CMakeLists.txt's brdfz_simd enables; level_of(HWY_TARGET) is the level a target
// serves) and, in its HWY_ONCE part, takes its builds with BRDFZ_HWY_BUILDS(Fn) and calls
// HwyBuilds::at(level). Highway's own HWY_EXPORT and HWY_DYNAMIC_DISPATCH are not used: they call into
// libhwy.so, which brdfz does not link.
//
//   level          x86-64                          ARM64
//   Sse2 (Neon)    SSE4, or SCALAR on a CPU        NEON
//                  without SSE4.2 (or with
//                  baseline_sse4 cleared)
//   Avx2Fma (Sve)  AVX2                            SVE
//   Avx512 (Sve2)  AVX3 (AVX-512 F, VL, DQ, BW)    SVE2
//
// A level's CPU test is cpu_simd()'s (brdfz/runtime/kernels/simd.h), so a build runs only where the CPU has
// its instructions; a target the compiler did not build falls to the next narrower one. Private to the
// library and brdfz::runtime (on their include path through the root CMakeLists.txt's brdfz_simd).
#pragma once

#include <cstdint>
#include <type_traits>

#include <hwy/detect_targets.h>

#include "brdfz/runtime/kernels/simd.h"

namespace brdfz::runtime::kernels {

// The level a Highway target's build serves, for kernels whose body depends on it (their lane counts).
constexpr Simd level_of(std::int64_t target) {
    if (target == HWY_AVX3 || target == HWY_SVE2) return Simd::Avx512;
    if (target == HWY_AVX2 || target == HWY_SVE) return Simd::Avx2Fma;
    return Simd::Sse2;
}

template <typename Fn>
struct HwyBuilds {
    Fn* fallback;  // the baseline target: SCALAR on x86-64, NEON on ARM64
    Fn* sse4;
    Fn* avx2;
    Fn* avx3;
    Fn* sve;
    Fn* sve2;

    Fn* at(Simd level) const {
        if (level >= Simd::Avx512 && avx3) return avx3;
        if (level >= Simd::Sve2 && sve2) return sve2;
        if (level >= Simd::Avx2Fma && avx2) return avx2;
        if (level >= Simd::Sve && sve) return sve;
        return sse4 && cpu_has_sse4() && baseline_sse4.load(std::memory_order_relaxed) ? sse4 : fallback;
    }
};

}  // namespace brdfz::runtime::kernels

// The builds of Fn, a function declared in each target's namespace (HWY_NAMESPACE) of the including
// file; null where a target was not compiled. Only after hwy/highway.h, in the file's `#if HWY_ONCE` part.
#define BRDFZ_HWY_BUILDS(Fn)                                                                              \
    ::brdfz::runtime::kernels::HwyBuilds<std::remove_pointer_t<decltype(HWY_CHOOSE_FALLBACK(Fn))>> {                \
        HWY_CHOOSE_FALLBACK(Fn), HWY_CHOOSE_SSE4(Fn), HWY_CHOOSE_AVX2(Fn), HWY_CHOOSE_AVX3(Fn), HWY_CHOOSE_SVE(Fn), \
            HWY_CHOOSE_SVE2(Fn)                                                                           \
    }
