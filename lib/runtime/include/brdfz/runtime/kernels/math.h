// Elementary functions the kernels share, without libm calls: a call cannot be vectorised and costs
// more than these branch-free forms. C++17 and the standard library only, as all of brdfz::runtime;
// the core's kernels use these same functions (one source, the same bits). Always inlined (GCC and
// Clang): a call in a loop over lanes keeps the loop from vectorising.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace brdfz::runtime::kernels {

constexpr double kPi = 3.141592653589793238462643383279502884;

template <typename To, typename From>
inline To bits_as(const From& from) {
    static_assert(sizeof(To) == sizeof(From), "bits_as: sizes differ");
    To to;
    std::memcpy(&to, &from, sizeof to);
    return to;
}

// c + a·b (madd) and c − a·b (nmadd), each one fused multiply-add where Fused, else a rounded product
// and a rounded sum. A kernel that takes Fused passes it from its build's level (factored.h,
// factor_fused), so that whether it fuses is in its code, not in its file's compiler flags; std::fma is
// one instruction in a build for a CPU with FMA, and a correctly rounded libm call elsewhere (the same
// bits, slowly). The unfused forms are the kernels' own expressions, c + a·b: GCC compiles the same
// values in another operand order to other, slower vector code.
template <bool Fused, typename T>
[[gnu::always_inline]] inline T madd(T a, T b, T c) {
    if constexpr (Fused)
        return std::fma(a, b, c);
    else
        return c + a * b;
}
template <bool Fused, typename T>
[[gnu::always_inline]] inline T nmadd(T a, T b, T c) {
    if constexpr (Fused)
        return std::fma(-a, b, c);
    else
        return c - a * b;
}

// atan(t) for t in [0, 1] as t·P(t²), a least-squares fit of the relative error: |rel err| < 6e-11.
// Estrin's scheme: a dependency chain of 4 multiply-adds instead of Horner's 11.
template <bool Fused = false>
[[gnu::always_inline]] inline double atan01(double t) {
    constexpr double c[] = {0.99999999994136979,   -0.33333331572392677, 0.19999912082711904,
                            -0.1428398114194897,   0.1109324385371387,   -0.089802498131937941,
                            0.072457466235865964,  -0.054279596397618646, 0.034210157407729216,
                            -0.016112066961960693, 0.0048510884142120014, -0.00068481937721016906};
    const double x = t * t, x2 = x * x, x4 = x2 * x2, x8 = x4 * x4;
    if constexpr (Fused) {
        const auto m = [](double a, double b, double c) { return std::fma(a, b, c); };
        const double p01 = m(c[1], x, c[0]), p23 = m(c[3], x, c[2]), p45 = m(c[5], x, c[4]), p67 = m(c[7], x, c[6]);
        const double p89 = m(c[9], x, c[8]), pab = m(c[11], x, c[10]);
        const double q0 = m(p23, x2, p01), q1 = m(p67, x2, p45), q2 = m(pab, x2, p89);
        return t * m(q2, x8, m(q1, x4, q0));
    } else {
        // Plain expressions: through madd, GCC compiles the RGL kernels' calls to other, slower code.
        const double p01 = c[0] + c[1] * x, p23 = c[2] + c[3] * x, p45 = c[4] + c[5] * x, p67 = c[6] + c[7] * x;
        const double p89 = c[8] + c[9] * x, pab = c[10] + c[11] * x;
        const double q0 = p01 + p23 * x2, q1 = p45 + p67 * x2, q2 = p89 + pab * x2;
        return t * ((q0 + q1 * x4) + q2 * x8);
    }
}

// The angle of (x, y) folded into [0, π] (φ ~ φ + π, as MERL folds φd by reciprocity), to ~1e-10
// relative. No branch: octant tests on random directions would mispredict half the time, and
// branch-free code vectorises. A NaN x gives NaN (a NaN y alone does not); (0, 0) gives NaN.
template <bool Fused = false>
[[gnu::always_inline]] inline double fast_half_turn_angle(double y, double x) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    const double a = atan01<Fused>(std::min(ax, ay) / std::max(ax, ay));
    const double steep = ay > ax ? 1.0 : 0.0, left = (x < 0.0) != (y < 0.0) ? 1.0 : 0.0;
    const double b = madd<Fused>(steep, nmadd<Fused>(2.0, a, kPi / 2), a);  // π/2 - a when |y| > |x|
    return madd<Fused>(left, nmadd<Fused>(2.0, b, kPi), b);                  // π - b in the 2nd quadrant
}

// sin and cos of a in [0, π] without a table or a branch: a is reduced to |b| ≤ π/4 by the quarter
// turn it lies nearest (0, π/2 or π), where Taylor series of 9 and 10 terms are below 1e-19 from sin
// and cos. Within a few ulp of 1 of std::sin and std::cos, and of sin a itself for small a.
struct SinCos {
    double s, c;
};
[[gnu::always_inline]] inline SinCos sincos_half_turn(double a) {
    constexpr double kQuarter = kPi / 4, kHalf = kPi / 2;
    const bool low = a <= kQuarter, high = a > 3 * kQuarter;
    const double b = low ? a : (high ? kPi - a : a - kHalf);
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

// e^x − 1 for x ≥ 0 (x above 709 is taken as 709, where e^x is near the double range's end), within
// 2e-16 relative of std::expm1 (tests/lib/fast_math_test.cpp). x = k·ln2 + r with |r| ≤ ln2/2, then
// e^x − 1 = 2^k·(e^r − 1) + (2^k − 1): the series for e^r − 1 keeps small x's relative accuracy.
inline double expm1_nonneg(double x) {
    x = x < 709.0 ? x : 709.0;
    constexpr double kShift = 0x1.8p52;  // x·log2(e) + kShift rounds to an integer in the low bits
    const double t = x * 1.44269504088896340736 + kShift;
    const double k = t - kShift;
    const std::int64_t ki = bits_as<std::int64_t>(t) - bits_as<std::int64_t>(kShift);
    const double scale = bits_as<double>((ki + 1023) << 52);  // 2^k
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
template <bool Fused = false>
inline double expm1_nonneg_f(float x) {
    x = x < 709.0f ? x : 709.0f;
    constexpr float kShift = 0x1.8p23f;  // x·log2(e) + kShift rounds to an integer k ≤ 1023 in the low bits
    const float t = madd<Fused>(x, 1.44269504088896340736f, kShift);
    const float k = t - kShift;
    const std::int64_t ki = bits_as<std::int32_t>(t) - bits_as<std::int32_t>(kShift);
    const double scale = bits_as<double>((ki + 1023) << 52);  // 2^k
    // kLn2Hi has 13 significant bits, so k·kLn2Hi is exact for k < 2^11.
    constexpr float kLn2Hi = 0x1.62ep-1f, kLn2Lo = static_cast<float>(0.693147180559945309417 - 0x1.62ep-1);
    const float r = nmadd<Fused>(k, kLn2Lo, nmadd<Fused>(k, kLn2Hi, x));
    // e^r − 1 = r·Σ r^i/(i+1)!, i ≤ 6: the truncation is < 2e-8 relative for |r| ≤ ln2/2.
    constexpr float c[] = {1.0f, 1.0f / 2, 1.0f / 6, 1.0f / 24, 1.0f / 120, 1.0f / 720, 1.0f / 5040};
    const float r2 = r * r, r4 = r2 * r2;
    const float p01 = madd<Fused>(c[1], r, c[0]), p23 = madd<Fused>(c[3], r, c[2]), p45 = madd<Fused>(c[5], r, c[4]);
    const float em = r * madd<Fused>(madd<Fused>(c[6], r2, p45), r4, madd<Fused>(p23, r2, p01));
    return madd<Fused>(scale, static_cast<double>(em), scale - 1.0);
}

// IEEE binary16 -> binary32, exact for every code (subnormals without float denormals, so it stays
// exact under flush-to-zero modes).
inline float half_to_float(std::uint16_t h) {
    const std::uint32_t em = h & 0x7fffu, sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
    const float normal = bits_as<float>((em << 13) + (112u << 23));  // rebias 15 -> 127
    const float subnormal = static_cast<float>(static_cast<int>(em)) * 0x1p-24f;
    const std::uint32_t special = 0x7f800000u | ((em & 0x3ffu) << 13);  // Inf, NaN
    const std::uint32_t bits = em >= 0x7c00u ? special : bits_as<std::uint32_t>(em < 0x400u ? subnormal : normal);
    return bits_as<float>(bits | sign);
}

}  // namespace brdfz::runtime::kernels
