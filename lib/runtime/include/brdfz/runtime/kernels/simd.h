// How a kernel gets its builds, in one place for the library and brdfz::runtime alike. A kernel is
// written once (a template over its level: its lane count, its vector width) and wrapped once per level
// by Builds below, in a [[gnu::flatten]] function carrying that level's attribute; build_for picks the
// wrapper for the level the CPU allows, at run time.
//
// Only x86-64 has levels beyond its baseline (SSE2) for these builds: AVX2 and AVX-512. Elsewhere (ARM64,
// whose baseline has NEON) they run their baseline build and the attributes name no instruction set.
// The library's Highway kernels (lib/src/detail/hwy_dispatch.h) have ARM64 levels too: SVE and SVE2.
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
// Highway build (lib/src/detail/hwy_dispatch.h), which CPUs without it run in its scalar form.
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

// The widest level both the CPU and simd_cap allow (brdfz::simd_level() for code outside the core).
inline Simd simd_level() {
    const Simd cpu = cpu_simd(), cap = simd_cap.load(std::memory_order_relaxed);
    return cpu < cap ? cpu : cap;
}

// A kernel's build at the level: avx512 where given and allowed, else avx2, else the baseline. Levels
// are ordered: a kernel without an AVX-512 build runs its AVX2 one at Avx512.
template <typename F>
F* build_for(Simd level, F* baseline, F* avx2, F* avx512 = nullptr) {
    if (level >= Simd::Avx512 && avx512) return avx512;
    return level >= Simd::Avx2Fma ? avx2 : baseline;
}

// A kernel's builds from its one body. K provides `template <Simd S> static R run(A...)`, the body at
// level S (its lane count, its vector width), and `static constexpr bool kAvx512` (whether it has a build
// of its own there) and `kFma` (whether its AVX2 build may contract: its builds then need not agree to
// the bit). Builds wraps run once per level, [[gnu::flatten]] with the level's attribute, so that the
// whole body is compiled for it; at(level) is the build for the level (build_for's rules).
template <typename K, typename Signature>
struct Builds;
template <typename K, typename R, typename... A>
struct Builds<K, R(A...)> {
    using Fn = R(A...);
    [[gnu::flatten]] static R baseline(A... a) { return K::template run<Simd::Sse2>(a...); }
    [[gnu::flatten, BRDFZ_AVX2]] static R avx2(A... a) { return K::template run<Simd::Avx2Fma>(a...); }
    [[gnu::flatten, BRDFZ_AVX2_FMA]] static R avx2_fma(A... a) { return K::template run<Simd::Avx2Fma>(a...); }
    [[gnu::flatten, BRDFZ_AVX512]] static R avx512(A... a) { return K::template run<Simd::Avx512>(a...); }
    static Fn* at(Simd level) {
        Fn* wide = nullptr;
        if constexpr (K::kAvx512) wide = avx512;
        if constexpr (K::kFma) return build_for<Fn>(level, baseline, avx2_fma, wide);
        else return build_for<Fn>(level, baseline, avx2, wide);
    }
};

}  // namespace runtime::kernels
}  // namespace brdfz
