// The kernels' SIMD levels and what the CPU runs, in one place for the library and brdfz::runtime. Each
// kernel is compiled once per Highway target and picked at run time for the level
// (lib/runtime/src/hwy_dispatch.h maps the levels to the targets); a level's build runs only where the
// CPU passes its test below.
#pragma once

#include <atomic>

#if defined(__aarch64__) && defined(__linux__)
#include <sys/auxv.h>
#endif

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define BRDFZ_X86 1
#else
#define BRDFZ_X86 0
#endif

namespace brdfz {

// The kernels' builds, ordered: the baseline (SSE2 on x86-64; NEON on ARM64), and x86-64's AVX2 and
// AVX-512 (F, DQ, VL and BW: x86-64-v4), which are ARM64's SVE and SVE2.
enum class Simd { Sse2, Avx2Fma, Avx512, Neon = Sse2, Sve = Avx2Fma, Sve2 = Avx512 };

namespace runtime::kernels {

// The widest level this CPU runs.
inline Simd cpu_simd() {
#if BRDFZ_X86
    // BMI1 and BMI2 come with every AVX2 CPU; the library's AVX2 builds (Highway's target) may use them.
    static const bool avx2_fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                                 __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    static const bool avx512 = avx2_fma && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw");
    return avx512 ? Simd::Avx512 : avx2_fma ? Simd::Avx2Fma : Simd::Sse2;
#elif defined(__aarch64__) && defined(__linux__)
    // Linux's HWCAP_SVE and HWCAP2_SVE2 bits (asm/hwcap.h), spelled out for C libraries without them.
    static const bool sve = (getauxval(AT_HWCAP) & (1UL << 22)) != 0;
    static const bool sve2 = sve && (getauxval(AT_HWCAP2) & (1UL << 1)) != 0;
    return sve2 ? Simd::Sve2 : sve ? Simd::Sve : Simd::Neon;
#else
    return Simd::Sse2;
#endif
}

// Whether an x86-64 CPU has SSE4.2 and what comes with it (SSSE3, SSE4.1, POPCNT): the baseline level's
// Highway build (lib/runtime/src/hwy_dispatch.h), which CPUs without it run in its scalar form.
inline bool cpu_has_sse4() {
#if BRDFZ_X86
    static const bool sse4 = __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("sse4.1") &&
                             __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
    return sse4;
#else
    return false;
#endif
}

// Tests lower it to run the narrower builds on a CPU that has the wider ones; Avx512 is no cap. A
// runtime material takes its builds when it is opened.
inline std::atomic<Simd> simd_cap{Simd::Avx512};
// Tests clear it to run the baseline level's scalar form on a CPU with SSE4.2, as CPUs without it do.
inline std::atomic<bool> baseline_sse4{true};

// The widest level both the CPU and simd_cap allow (brdfz::simd_level() for code outside the core).
inline Simd simd_level() {
    const Simd cpu = cpu_simd(), cap = simd_cap.load(std::memory_order_relaxed);
    return cpu < cap ? cpu : cap;
}

}  // namespace runtime::kernels
}  // namespace brdfz
