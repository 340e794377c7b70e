// sin and cos without libm calls, for samplers whose loops over lanes must vectorise (a call cannot be
// vectorised): the analytic lobes' samplers (runtime/kernels/lobes/sampling.h) and the library's table kernels.
#pragma once

#include "brdfz/runtime/kernels/math.h"

namespace brdfz::detail {

// sin and cos of a in [0, π] without a table or a branch, so that the loops calling it vectorise with no
// gathers: the runtime's (brdfz/runtime/kernels/math.h), within a few ulp of std::sin and std::cos.
using SinCos2 = runtime::kernels::SinCos;
using runtime::kernels::sincos_half_turn;

}  // namespace brdfz::detail
