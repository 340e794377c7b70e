// The kernels' levels are the runtime's (brdfz/runtime/kernels/simd.h), one place for the library and
// brdfz::runtime.
#pragma once

#include "brdfz/runtime/kernels/simd.h"

namespace brdfz::detail {

using ::brdfz::Simd;
using runtime::kernels::simd_cap;
using runtime::kernels::simd_level;

}  // namespace brdfz::detail
