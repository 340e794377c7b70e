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
