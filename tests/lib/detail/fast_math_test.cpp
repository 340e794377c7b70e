#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

TEST_CASE("fast math: expm1_nonneg_f matches std::expm1 to float accuracy", "[fast_math]") {
    double worst = 0.0;
    for (float x = 1e-38f; x < 709.0f; x *= 1.0001f) {
        const double e = std::expm1(static_cast<double>(x));
        worst = std::max(worst, std::fabs(detail::expm1_nonneg_f(x) - e) / e);
    }
    CHECK(worst < 3e-7);  // a few float ulp
    CHECK(detail::expm1_nonneg_f(0.0f) == 0.0);
    // 88.8 would overflow a float result: the scaling is in double
    CHECK(detail::expm1_nonneg_f(88.8f) == Approx(std::expm1(static_cast<double>(88.8f))).epsilon(3e-7));
    CHECK(detail::expm1_nonneg_f(1e6f) == Approx(std::expm1(709.0)).epsilon(3e-7));  // taken as 709: finite
    CHECK(std::isfinite(detail::expm1_nonneg_f(std::numeric_limits<float>::infinity())));
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

TEST_CASE("fast math: fast_half_turn_angle matches atan2 folded to [0, pi]", "[fast_math]") {
    double worst = 0.0;
    for (int k = 0; k < 100000; ++k) {
        const double phi = 2.0 * std::numbers::pi * (k + 0.5) / 100000, y = std::sin(phi), x = std::cos(phi);
        double ref = std::atan2(y, x);
        if (ref < 0.0) ref += std::numbers::pi;
        worst = std::max(worst, std::fabs(detail::fast_half_turn_angle(y, x) - ref));
    }
    CHECK(worst < 1e-9);
    CHECK(std::isnan(detail::fast_half_turn_angle(1.0, std::nan(""))));  // NaN x: NaN
}
