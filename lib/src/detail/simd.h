// The instruction set a batch kernel may use beyond the x86-64 baseline (SSE2) the library is compiled
// for, chosen at run time: a kernel built twice (the second with [[gnu::target("avx2,fma")]]) runs the
// wider one only where the CPU has it.
#pragma once

#include <atomic>

namespace brdfz::detail {

enum class Simd { Sse2, Avx2Fma };

// Tests lower it to run the baseline kernels on a CPU that has AVX2.
inline std::atomic<Simd> simd_cap{Simd::Avx2Fma};

// The widest level both the CPU and simd_cap allow.
inline Simd simd_level() {
#if defined(__x86_64__) || defined(__i386__)
    static const bool avx2_fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    constexpr bool avx2_fma = false;
#endif
    return avx2_fma && simd_cap.load(std::memory_order_relaxed) == Simd::Avx2Fma ? Simd::Avx2Fma : Simd::Sse2;
}

}  // namespace brdfz::detail
