// sin and cos without libm calls, for samplers whose loops over lanes must vectorise (a call cannot be
// vectorised): the analytic lobes' samplers (repr/analytic/sampling.h) and the library's table kernels.
#pragma once

#include <numbers>

namespace brdfz::detail {

// sin and cos of a in [0, π] without a table or a branch, so that the loops calling it vectorise with no
// gathers: a is reduced to |b| ≤ π/4 by the quarter turn it lies nearest (0, π/2 or π), where Taylor
// series of 9 and 10 terms are below 1e-19 from sin and cos. Within a few ulp of 1 of std::sin and
// std::cos, and of sin a itself for small a (tests/lib/detail/fast_math_test.cpp). `a` must lie in [0, π].
struct SinCos2 {
    double s, c;
};
[[gnu::always_inline]] inline SinCos2 sincos_half_turn(double a) {
    constexpr double kQuarter = std::numbers::pi / 4, kHalf = std::numbers::pi / 2;
    const bool low = a <= kQuarter, high = a > 3 * kQuarter;
    const double b = low ? a : (high ? std::numbers::pi - a : a - kHalf);
    const double x = b * b;
    // sin b = b Σ (−x)^i/(2i+1)!, cos b = Σ (−x)^i/(2i)!, by Horner (the terms fall off fast).
    const double sb = b * (1.0 + x * (-1.0 / 6 + x * (1.0 / 120 + x * (-1.0 / 5040 + x * (1.0 / 362880 +
                       x * (-1.0 / 39916800 + x * (1.0 / 6227020800 + x * (-1.0 / 1307674368000 +
                       x * (1.0 / 355687428096000)))))))));
    const double cb = 1.0 + x * (-0.5 + x * (1.0 / 24 + x * (-1.0 / 720 + x * (1.0 / 40320 + x * (-1.0 / 3628800 +
                      x * (1.0 / 479001600 + x * (-1.0 / 87178291200 + x * (1.0 / 20922789888000 +
                      x * (-1.0 / 6402373705728000)))))))));
    // a = b, π − b or π/2 + b.
    const bool mid = !low & !high;
    return {mid ? cb : sb, low ? cb : (high ? -cb : -sb)};
}

}  // namespace brdfz::detail
