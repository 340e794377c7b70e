// How a batch kernel gets its builds, in one place. A kernel is written once (a template over its lane
// count, or one body) and wrapped once per level in a [[gnu::flatten]] function carrying that level's
// attribute below; build_for picks the wrapper for the level the CPU allows, at run time.
//
// Only x86-64 has levels beyond its baseline (SSE2): AVX2 and AVX-512. Elsewhere (ARM64, whose baseline
// has NEON) every kernel runs its baseline build, the attributes name no instruction set, and
// simd_level() is always Simd::Sse2, "the baseline".
#pragma once

#include <atomic>

#include "brdfz/simd.h"

#if defined(__x86_64__) || defined(__i386__)
#define BRDFZ_X86 1
#else
#define BRDFZ_X86 0
#endif

namespace brdfz::detail {

using ::brdfz::Simd;

// Tests lower it to run the narrower builds on a CPU that has the wider ones; Avx512 is no cap.
inline std::atomic<Simd> simd_cap{Simd::Avx512};

// The widest level both the CPU and simd_cap allow (brdfz::simd_level() for code outside the core).
// Levels are ordered: a kernel without an AVX-512 build runs its AVX2 one at Avx512.
inline Simd simd_level() {
#if BRDFZ_X86
    static const bool avx2_fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    static const bool avx512 = avx2_fma && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw");
#else
    constexpr bool avx2_fma = false, avx512 = false;
#endif
    const Simd cap = simd_cap.load(std::memory_order_relaxed);
    if (avx512 && cap >= Simd::Avx512) return Simd::Avx512;
    return avx2_fma && cap >= Simd::Avx2Fma ? Simd::Avx2Fma : Simd::Sse2;
}

// A kernel's build at the level: avx512 where given and allowed, else avx2, else the baseline.
template <typename F>
F* build_for(Simd level, F* baseline, F* avx2, F* avx512 = nullptr) {
    if (level >= Simd::Avx512 && avx512) return avx512;
    return level >= Simd::Avx2Fma ? avx2 : baseline;
}

}  // namespace brdfz::detail

// The levels' attributes. AVX2 comes without FMA: its contraction would round differently from the
// baseline build, and the builds give the same bits. AVX-512 asks for 512-bit vectors (GCC and clang
// otherwise prefer 256-bit ones even where AVX-512 is enabled; clang with its own attribute); it has
// FMA, which the library's -ffp-contract=off keeps from contracting. BRDFZ_AVX2_FMA is for a kernel
// whose builds need not agree to the bit (factored eval, within its float rounding).
#if BRDFZ_X86
#define BRDFZ_AVX2 gnu::target("avx2")
#define BRDFZ_AVX2_FMA gnu::target("avx2,fma")
#if defined(__clang__)
#define BRDFZ_AVX512 gnu::target("avx512f,avx512dq,avx512vl,avx512bw"), clang::min_vector_width(512)
#else
#define BRDFZ_AVX512 gnu::target("avx512f,avx512dq,avx512vl,avx512bw,prefer-vector-width=512")
#endif
#else
#define BRDFZ_AVX2
#define BRDFZ_AVX2_FMA
#define BRDFZ_AVX512
#endif
