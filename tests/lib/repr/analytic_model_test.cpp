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

TEST_CASE("default sampling is cosine-weighted, consistent with pdf and eval", "[sample][conventions]") {
    const CoatedDiffuse m;
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const Vec3 wo = normalize({0.3, -0.2, 0.8});
    double mean_cos = 0;
    const int n = 100000;
    for (int k = 0; k < n; ++k) {
        const BrdfSample s = m.sample(wo, u(rng), u(rng));
        REQUIRE(s.pdf > 0.0);
        CHECK(s.pdf == Approx(m.pdf(wo, s.wi)).epsilon(1e-12));
        const Rgb f = m.eval(s.wi, wo);
        CHECK(s.weight[1] == Approx(f[1] * s.wi.z / s.pdf).epsilon(1e-12));
        mean_cos += s.wi.z / n;
    }
    CHECK(mean_cos == Approx(2.0 / 3.0).epsilon(0.01));  // E[cosθ] under cosθ/π
    // Failed samples: wo below the horizon, u outside [0, 1).
    CHECK(m.sample({0, 0, -1}, 0.5, 0.5).pdf == 0.0);
    CHECK(m.sample(wo, 1.0, 0.5).pdf == 0.0);
    CHECK(m.sample(wo, std::nan(""), 0.5).pdf == 0.0);
    CHECK(m.pdf(wo, {0, 0, -1}) == 0.0);
}
