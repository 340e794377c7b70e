// The instruction set a batch kernel may use beyond the x86-64 baseline (SSE2) the library is compiled
// for, chosen at run time: a kernel built more than once (with [[gnu::target("avx2")]], or the
// AVX-512 attribute below) runs the widest build the CPU has. Levels are ordered: a kernel without an
// AVX-512 build runs its AVX2 one at Avx512.
#pragma once

#include <atomic>

#include "brdfz/simd.h"

namespace brdfz::detail {

using ::brdfz::Simd;

// Tests lower it to run the narrower builds on a CPU that has the wider ones; Avx512 is no cap.
inline std::atomic<Simd> simd_cap{Simd::Avx512};

// The widest level both the CPU and simd_cap allow (brdfz::simd_level() for code outside the core).
inline Simd simd_level() {
#if defined(__x86_64__) || defined(__i386__)
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

}  // namespace brdfz::detail

// The target attribute of AVX-512 builds: 512-bit vectors (GCC and clang otherwise prefer 256-bit ones
// even where AVX-512 is enabled; clang asks for them with its own attribute). Without FMA contraction
// where a kernel must give its other builds' bits, which the unit's -ffp-contract=off provides.
#if defined(__clang__)
#define BRDFZ_AVX512 gnu::target("avx512f,avx512dq,avx512vl,avx512bw"), clang::min_vector_width(512)
#else
#define BRDFZ_AVX512 gnu::target("avx512f,avx512dq,avx512vl,avx512bw,prefer-vector-width=512")
#endif
