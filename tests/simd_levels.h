// The SIMD builds of the kernels (runtime/kernels/simd.h) that this CPU runs, for tests that compare them.
#pragma once

#include <vector>

#include "detail/simd.h"

namespace brdfz::test {

// The levels the CPU has, narrowest first (Sse2 always).
inline std::vector<detail::Simd> simd_levels() {
    std::vector<detail::Simd> levels;
    for (detail::Simd s : {detail::Simd::Sse2, detail::Simd::Avx2Fma, detail::Simd::Avx512}) {
        detail::simd_cap = s;
        if (detail::simd_level() == s) levels.push_back(s);
    }
    detail::simd_cap = detail::Simd::Avx512;
    return levels;
}

inline const char* simd_label(detail::Simd s) {
#if BRDFZ_X86
    return s == detail::Simd::Avx512 ? "AVX-512" : s == detail::Simd::Avx2Fma ? "AVX2" : "SSE2";
#else
    return s == detail::Simd::Sve2 ? "SVE2" : s == detail::Simd::Sve ? "SVE" : "baseline";
#endif
}

// Caps the level for its scope; no cap again on exit.
struct SimdCap {
    explicit SimdCap(detail::Simd s) { detail::simd_cap = s; }
    ~SimdCap() { detail::simd_cap = detail::Simd::Avx512; }
    SimdCap(const SimdCap&) = delete;
    SimdCap& operator=(const SimdCap&) = delete;
};

}  // namespace brdfz::test
