#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "brdfz/coords.h"

using namespace brdfz;

namespace {
Vec3 random_upper(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double z = u(rng), phi = 2 * std::numbers::pi * u(rng);
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}
double dist(const Vec3& a, const Vec3& b) { return length(a - b); }
}  // namespace

TEST_CASE("Rusinkiewicz round trip on 10^6 random pairs", "[coords]") {
    std::mt19937_64 rng(7);
    double worst = 0;
    for (int k = 0; k < 1000000; ++k) {
        const Vec3 wi = random_upper(rng), wo = random_upper(rng);
        const auto [wi2, wo2] = from_half_diff(to_half_diff(wi, wo));
        worst = std::max({worst, dist(wi, wi2), dist(wo, wo2)});
    }
    CHECK(worst < 1e-9);
}

TEST_CASE("Rusinkiewicz coordinates are finite at the pole, at grazing and for opposite directions", "[coords]") {
    const Vec3 n{0, 0, 1};
    const Vec3 cases[][2] = {
        {n, n},                                    // wi = wo = normal
        {{1, 0, 0}, {-1, 0, 0}},                   // opposite at grazing: no unique half vector
        {{1, 0, 0}, {1, 0, 0}},                    // grazing, equal
        {{0, 1, 0}, {1, 0, 0}},                    // grazing, perpendicular
        {{1, 0, 1e-300}, {-1, 0, 1e-300}},         // nearly opposite
        {normalize({1, 0, 1e-9}), normalize({-1, 1e-12, 1e-9})},
    };
    for (const auto& c : cases) {
        const HalfDiff hd = to_half_diff(c[0], c[1]);
        CHECK(std::isfinite(hd.theta_h));
        CHECK(std::isfinite(hd.phi_h));
        CHECK(std::isfinite(hd.theta_d));
        CHECK(std::isfinite(hd.phi_d));
        const auto [wi, wo] = from_half_diff(hd);
        CHECK(dist(wi, c[0]) < 1e-9);
        CHECK(dist(wo, c[1]) < 1e-6);  // the half vector of nearly opposite pairs is ill-conditioned
    }
    const HalfDiff pole = to_half_diff(n, n);
    CHECK(pole.theta_h == 0.0);
    CHECK(pole.theta_d == 0.0);
    const HalfDiff opposite = to_half_diff({1, 0, 0}, {-1, 0, 0});
    CHECK(opposite.theta_h == 0.0);
    CHECK(opposite.theta_d == Approx(M_PI / 2));
}

TEST_CASE("from_half_diff then to_half_diff recovers the angles", "[coords]") {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double worst = 0;
    for (int k = 0; k < 100000; ++k) {
        const HalfDiff hd{u(rng) * M_PI / 2, (2 * u(rng) - 1) * M_PI, u(rng) * M_PI / 2, (2 * u(rng) - 1) * M_PI};
        const auto [wi, wo] = from_half_diff(hd);
        const HalfDiff back = to_half_diff(wi, wo);
        worst = std::max({worst, std::fabs(back.theta_h - hd.theta_h), std::fabs(back.theta_d - hd.theta_d),
                          std::fabs(std::remainder(back.phi_d - hd.phi_d, 2 * M_PI)) * std::sin(hd.theta_d),
                          std::fabs(std::remainder(back.phi_h - hd.phi_h, 2 * M_PI)) * std::sin(hd.theta_h)});
    }
    CHECK(worst < 1e-9);
}

TEST_CASE("elevation is accurate near the pole where acos(z) is not", "[coords][conventions]") {
    for (double t : {1e-12, 1e-8, 1e-4, 0.5, 1.5, 2.5, M_PI - 1e-9}) {
        const Vec3 v = spherical_direction(t, 0.7);
        CHECK(elevation(v) == Approx(t).epsilon(1e-12));
    }
}
