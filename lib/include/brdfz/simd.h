// Which instruction set the batch kernels (Brdf's eval, pdf and sample over spans) run with here.
#pragma once

namespace brdfz {

// The kernels' builds, ordered: the baseline (SSE2 on x86-64; on other CPUs the only build, NEON on
// ARM64), and x86-64's AVX2 and AVX-512 (F, DQ, VL and BW: x86-64-v4).
enum class Simd { Sse2, Avx2Fma, Avx512 };

// The widest build the CPU runs, chosen at run time; a kernel without a build at that width runs its
// next narrower one.
Simd simd_level();
// "avx512", "avx2" or "sse2" on x86-64, "neon" on ARM64: simd_level()'s name.
const char* simd_name();

}  // namespace brdfz
