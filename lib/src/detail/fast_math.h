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

// e^x − 1 for x ≥ 0 (x above 709 is taken as 709, where e^x is near the double range's end), within
// 2e-16 relative of std::expm1 (tests/lib/fast_math_test.cpp). x = k·ln2 + r with |r| ≤ ln2/2, then
// e^x − 1 = 2^k·(e^r − 1) + (2^k − 1): the series for e^r − 1 keeps small x's relative accuracy.
inline double expm1_nonneg(double x) {
    x = x < 709.0 ? x : 709.0;
    constexpr double kShift = 0x1.8p52;  // x·log2(e) + kShift rounds to an integer in the low bits
    const double t = x * std::numbers::log2e + kShift;
    const double k = t - kShift;
    const std::int64_t ki = std::bit_cast<std::int64_t>(t) - std::bit_cast<std::int64_t>(kShift);
    const double scale = std::bit_cast<double>((ki + 1023) << 52);  // 2^k
    constexpr double kLn2Hi = 0x1.62e42fee00000p-1, kLn2Lo = 0x1.a39ef35793c76p-33;  // k·kLn2Hi is exact
    const double r = (x - k * kLn2Hi) - k * kLn2Lo;
    // e^r − 1 = r·Σ r^i/(i+1)!, i ≤ 12: the truncation is < 5e-16 relative for |r| ≤ ln2/2. Estrin's
    // scheme keeps the dependency chain short.
    constexpr double c[] = {1.0,
                            1.0 / 2,
                            1.0 / 6,
                            1.0 / 24,
                            1.0 / 120,
                            1.0 / 720,
                            1.0 / 5040,
                            1.0 / 40320,
                            1.0 / 362880,
                            1.0 / 3628800,
                            1.0 / 39916800,
                            1.0 / 479001600,
                            1.0 / 6227020800};
    const double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
    const double p01 = c[0] + c[1] * r, p23 = c[2] + c[3] * r, p45 = c[4] + c[5] * r, p67 = c[6] + c[7] * r;
    const double p89 = c[8] + c[9] * r, pab = c[10] + c[11] * r;
    const double q0 = p01 + p23 * r2, q1 = p45 + p67 * r2, q2 = p89 + pab * r2 + c[12] * r4;
    const double em = r * ((q0 + q1 * r4) + q2 * r8);
    return scale * em + (scale - 1.0);
}

// e^x − 1 for a float x ≥ 0 (above 709 taken as 709), within ~2e-7 relative of std::expm1: for
// values blended in float (already ~1e-7 from exact), where expm1_nonneg's double polynomial buys no
// accuracy. The reduction and the 7-term series run in float (twice the SIMD lanes, half the terms);
// only the final scaling by 2^k is in double, so no x up to 709 overflows.
inline double expm1_nonneg_f(float x) {
    x = x < 709.0f ? x : 709.0f;
    constexpr float kShift = 0x1.8p23f;  // x·log2(e) + kShift rounds to an integer k ≤ 1023 in the low bits
    const float t = x * std::numbers::log2e_v<float> + kShift;
    const float k = t - kShift;
    const std::int64_t ki = std::bit_cast<std::int32_t>(t) - std::bit_cast<std::int32_t>(kShift);
    const double scale = std::bit_cast<double>((ki + 1023) << 52);  // 2^k
    // kLn2Hi has 13 significant bits, so k·kLn2Hi is exact for k < 2^11.
    constexpr float kLn2Hi = 0x1.62ep-1f, kLn2Lo = static_cast<float>(std::numbers::ln2 - 0x1.62ep-1);
    const float r = (x - k * kLn2Hi) - k * kLn2Lo;
    // e^r − 1 = r·Σ r^i/(i+1)!, i ≤ 6: the truncation is < 2e-8 relative for |r| ≤ ln2/2.
    constexpr float c[] = {1.0f, 1.0f / 2, 1.0f / 6, 1.0f / 24, 1.0f / 120, 1.0f / 720, 1.0f / 5040};
    const float r2 = r * r, r4 = r2 * r2;
    const float p01 = c[0] + c[1] * r, p23 = c[2] + c[3] * r, p45 = c[4] + c[5] * r;
    const float em = r * ((p01 + p23 * r2) + (p45 + c[6] * r2) * r4);
    return scale * em + (scale - 1.0);
}

// The arctangents are the runtime's (one source for the library, brdfz::runtime and the shaders).
using runtime::kernels::atan01;
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
