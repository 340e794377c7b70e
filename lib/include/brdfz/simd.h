// Which instruction set the batch kernels (Brdf's eval, pdf and sample over spans) run with here.
#pragma once

namespace brdfz {

// "avx512", "avx2" or "sse2": the widest build of the kernels the CPU runs, chosen at run time (a
// kernel without a build at that width runs its next narrower one).
const char* simd_name();

}  // namespace brdfz
