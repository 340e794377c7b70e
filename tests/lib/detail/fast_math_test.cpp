#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>

#include "detail/fast_math.h"

using namespace brdfz;

TEST_CASE("fast math: expm1_nonneg matches std::expm1 to 2e-16 relative", "[fast_math]") {
    double worst = 0.0;
    for (double x = 1e-300; x < 709.0; x *= 1.001) {
        const double e = std::expm1(x);
        worst = std::max(worst, std::fabs(detail::expm1_nonneg(x) - e) / e);
    }
    CHECK(worst < 5e-16);  // a few ulp
    CHECK(detail::expm1_nonneg(0.0) == 0.0);
    CHECK(detail::expm1_nonneg(1e6) == Approx(std::expm1(709.0)));  // taken as 709: finite
    CHECK(std::isfinite(detail::expm1_nonneg(std::numeric_limits<double>::infinity())));
}

// Fused: the forms with fused multiply-adds (math.h, madd), which the factored eval's FMA builds run,
// meet the same bounds.
TEMPLATE_TEST_CASE("fast math: expm1_nonneg_f matches std::expm1 to float accuracy", "[fast_math]", std::false_type,
                   std::true_type) {
    const auto expm1_f = [](float x) { return detail::expm1_nonneg_f<TestType::value>(x); };
    double worst = 0.0;
    for (float x = 1e-38f; x < 709.0f; x *= 1.0001f) {
        const double e = std::expm1(static_cast<double>(x));
        worst = std::max(worst, std::fabs(expm1_f(x) - e) / e);
    }
    CHECK(worst < 3e-7);  // a few float ulp
    CHECK(expm1_f(0.0f) == 0.0);
    // 88.8 would overflow a float result: the scaling is in double
    CHECK(expm1_f(88.8f) == Approx(std::expm1(static_cast<double>(88.8f))).epsilon(3e-7));
    CHECK(expm1_f(1e6f) == Approx(std::expm1(709.0)).epsilon(3e-7));  // taken as 709: finite
    CHECK(std::isfinite(expm1_f(std::numeric_limits<float>::infinity())));
}

TEST_CASE("fast math: SinCosTable matches std::sin and std::cos within a few ulp", "[fast_math]") {
    const detail::SinCosTable table(std::numbers::pi, 256);
    double worst = 0.0, worst_small = 0.0;
    for (int k = 0; k <= 1000000; ++k) {
        const double a = std::numbers::pi * k / 1000000;
        const auto sc = table(a);
        worst = std::max({worst, std::fabs(sc.s - std::sin(a)), std::fabs(sc.c - std::cos(a))});
        if (a > 0.0 && a < 1.0) worst_small = std::max(worst_small, std::fabs(sc.s - std::sin(a)) / std::sin(a));
    }
    CHECK(worst < 4.5e-16);  // 2 ulp of 1
    CHECK(worst_small < 6e-16);  // and relative where sin is small
    CHECK(table(0.0).s == 0.0);
    CHECK(table(0.0).c == 1.0);
}

TEMPLATE_TEST_CASE("fast math: fast_half_turn_angle matches atan2 folded to [0, pi]", "[fast_math]", std::false_type,
                   std::true_type) {
    const auto angle = [](double y, double x) { return detail::fast_half_turn_angle<TestType::value>(y, x); };
    double worst = 0.0;
    for (int k = 0; k < 100000; ++k) {
        const double phi = 2.0 * std::numbers::pi * (k + 0.5) / 100000, y = std::sin(phi), x = std::cos(phi);
        double ref = std::atan2(y, x);
        if (ref < 0.0) ref += std::numbers::pi;
        worst = std::max(worst, std::fabs(angle(y, x) - ref));
    }
    CHECK(worst < 1e-9);
    CHECK(std::isnan(angle(1.0, std::nan(""))));  // NaN x: NaN
}

TEST_CASE("fast math: sincos_half_turn matches std::sin and std::cos within a few ulp", "[fast_math]") {
    double worst = 0.0, worst_small = 0.0;
    const auto ulps = [](double a, double b) { return std::fabs(a - b) / (std::fabs(b) * 0x1p-52 + 1e-300); };
    for (int i = 0; i <= 2000000; ++i) {
        const double a = std::numbers::pi * i / 2000000;
        const detail::SinCos2 r = detail::sincos_half_turn(a);
        // Absolute within a few ulp of 1 everywhere (near π/2 and π, relative to the double π's rounding);
        // relative near 0, where the reduction leaves a as it is.
        worst = std::max({worst, std::fabs(r.s - std::sin(a)), std::fabs(r.c - std::cos(a))});
        if (a < 0.5) worst_small = std::max(worst_small, ulps(r.s, std::sin(a)));
    }
    CHECK(worst < 4e-16);
    CHECK(worst_small < 4.0);
    for (double a = 1e-300; a < 1e-3; a *= 1.7) CHECK(ulps(detail::sincos_half_turn(a).s, std::sin(a)) < 2.0);
    CHECK(detail::sincos_half_turn(0.0).s == 0.0);
    CHECK(detail::sincos_half_turn(0.0).c == 1.0);
}
