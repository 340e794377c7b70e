// Elementary functions for batch kernels, without libm calls: a call cannot be vectorised, and these
// are branch-free, so GCC vectorises the loops that use them (SSE2: two doubles at a time).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "brdfz/runtime/kernels/math.h"
#include "brdfz/sample/sincos.h"

namespace brdfz::detail {

// The arctangents and exponentials are the runtime's (one source for the library, brdfz::runtime and
// the shaders).
using runtime::kernels::atan01;
using runtime::kernels::expm1_nonneg;
using runtime::kernels::expm1_nonneg_f;
using runtime::kernels::fast_half_turn_angle;

// sin and cos of angles in [0, range] from a table at n + 1 equally spaced angles and the angle-addition
// formulas: a = a_i + δ with |δ| ≤ range/(2n), whose sine and cosine need only a few series terms. For
// n ≥ 64·range (|δ| ≤ 1/128) the truncation is below 1e-18 absolute, and the results are within a few
// ulp of std::sin and std::cos (tests/lib/fast_math_test.cpp). `a` must lie in [0, range].
class SinCosTable {
public:
    struct SinCos {
        double s, c;
    };
    SinCosTable(double range, int n) : step_(range / n), inv_step_(n / range), n_(n), table_(n + 1) {
        for (int i = 0; i <= n; ++i) table_[i] = {std::sin(i * step_), std::cos(i * step_)};
    }
    SinCos operator()(double a) const {
        // Clamped by selects, which take NaN to entry 0 (std::clamp passes NaN through, to an index far
        // outside the table): a NaN angle, as a sampler's masked-off lanes may compute, gives NaN, not a
        // wild read.
        const double r = a * inv_step_ + 0.5, lo = r > 0.5 ? r : 0.5, x = lo < n_ + 0.5 ? lo : n_ + 0.5;
        const int i = static_cast<int>(x);
        const double d = a - i * step_, d2 = d * d;
        const double sd = d * (1.0 - d2 * (1.0 / 6 - d2 * (1.0 / 120))),
                     cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24 - d2 * (1.0 / 720)));
        const SinCos& t = table_[i];
        return {t.s * cd + t.c * sd, t.c * cd - t.s * sd};
    }

private:
    double step_, inv_step_;
    int n_;
    std::vector<SinCos> table_;
};

// sin and cos over [0, π] for the samplers (half-vector azimuths and elevations), shared.
inline const SinCosTable& half_turn_sincos() {
    static const SinCosTable table(std::numbers::pi, 256);
    return table;
}

}  // namespace brdfz::detail
