#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "brdfz/albedo.h"
#include "brdfz/repr/analytic/coated_diffuse.h"

using namespace brdfz;

TEST_CASE("the built-in coated diffuse material is reciprocal, finite and conserves energy", "[analytic]") {
    const CoatedDiffuse m;
    std::mt19937_64 rng(9);
    std::normal_distribution<double> n;
    for (int k = 0; k < 10000; ++k) {
        Vec3 wi = normalize({n(rng), n(rng), n(rng)}), wo = normalize({n(rng), n(rng), n(rng)});
        wi.z = std::fabs(wi.z);
        wo.z = std::fabs(wo.z);
        const Rgb a = m.eval(wi, wo), b = m.eval(wo, wi);
        for (int c = 0; c < 3; ++c) {
            CHECK(std::isfinite(a[c]));
            CHECK(a[c] >= 0.0);
            CHECK(a[c] == Approx(b[c]).epsilon(1e-12));
        }
    }
    for (double deg : {0.0, 30.0, 60.0, 80.0, 89.0}) {
        const Rgb rho = directional_albedo(m, deg * M_PI / 180);
        for (double c : rho) {
            CHECK(c > 0.0);
            CHECK(c <= 1.0);
        }
    }
    CHECK_THROWS(CoatedDiffuse({{0.5, 0.5, 0.5}, 0.0, 1.5}));
    CHECK_THROWS(CoatedDiffuse({{0.5, std::nan(""), 0.5}, 0.1, 1.5}));
}
