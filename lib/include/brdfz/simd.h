// Which instruction set the batch kernels (Brdf's eval, pdf and sample over spans) run with here.
#pragma once

#include "brdfz/runtime/kernels/simd.h"  // enum class Simd, the kernels' builds in order

namespace brdfz {

// The widest build the CPU runs, chosen at run time; a kernel without a build at that width runs its
// next narrower one.
Simd simd_level();
// "avx512", "avx2" or "sse2" on x86-64, "sve2", "sve" or "neon" on ARM64: simd_level()'s name.
const char* simd_name();

}  // namespace brdfz
