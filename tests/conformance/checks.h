// The checks every representation kind and every file format passes (pbrt-v4's TestBSDF in spirit):
// conventions (brdf.h), batch = one call, reciprocity where declared, the sampler's χ², the white
// furnace, the container round trip and refusals. conformance_test.cpp runs them from one line per kind;
// formats are taken from the registry, so a new one is checked without a line.
#pragma once

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/brdf.h"
#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "sample_stats.h"
#include "test_util.h"

namespace brdfz::test {

// Random pairs over the whole sphere (a quarter below the horizon on either side).
inline std::pair<std::vector<Vec3>, std::vector<Vec3>> random_pairs(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = normalize({g(rng), g(rng), g(rng)});
        wo[k] = normalize({g(rng), g(rng), g(rng)});
        if (k % 4) wi[k].z = std::fabs(wi[k].z), wo[k].z = std::fabs(wo[k].z);
    }
    return {wi, wo};
}

inline void check_close(const Rgb& a, const Rgb& b, double rel) {
    for (int c = 0; c < 3; ++c) REQUIRE(a[c] == Approx(b[c]).epsilon(rel).margin(1e-12));
}

// brdf.h's conventions, and batches equal to one call at a time.
inline void check_conventions(const Brdf& b) {
    const auto [wi, wo] = random_pairs(2000, 11);
    std::vector<Rgb> batch(wi.size()), batch_cos(wi.size());
    b.eval(std::span(wi), std::span(wo), std::span(batch));
    b.eval_cos(std::span(wi), std::span(wo), std::span(batch_cos));
    for (std::size_t k = 0; k < wi.size(); ++k) {
        const Rgb f = b.eval(wi[k], wo[k]);
        for (int c = 0; c < 3; ++c) {
            REQUIRE(std::isfinite(f[c]));
            REQUIRE(f[c] >= 0.0);
            if (!(wi[k].z > 0 && wo[k].z > 0)) REQUIRE(f[c] == 0.0);
            REQUIRE(b.eval_cos(wi[k], wo[k])[c] == Approx(f[c] * std::fmax(wi[k].z, 0.0)).margin(1e-12));
        }
        INFO("batch eval against one call, pair " << k);
        check_close(batch[k], f, 1e-6);
        check_close(batch_cos[k], b.eval_cos(wi[k], wo[k]), 1e-6);
    }
    // Draws: batches equal single calls; pdf agrees with the draw and vanishes below the horizon.
    auto [views, us] = random_views(500, 12);
    std::vector<BrdfSample> drawn(views.size());
    b.sample(std::span<const Vec3>(views), std::span<const std::array<double, 2>>(us), std::span(drawn));
    std::vector<double> pdfs(views.size());
    std::vector<Vec3> drawn_wi(views.size());
    for (std::size_t k = 0; k < views.size(); ++k) drawn_wi[k] = drawn[k].wi;
    b.pdf(std::span<const Vec3>(views), std::span<const Vec3>(drawn_wi), std::span(pdfs));
    for (std::size_t k = 0; k < views.size(); ++k) {
        const BrdfSample s = b.sample(views[k], us[k][0], us[k][1]);
        REQUIRE(drawn[k].pdf == Approx(s.pdf).epsilon(1e-6).margin(1e-12));
        check_close(drawn[k].weight, s.weight, 1e-6);
        if (s.pdf == 0) continue;
        REQUIRE(s.wi.z > 0);
        REQUIRE(pdfs[k] == Approx(s.pdf).epsilon(1e-6));
        REQUIRE(b.pdf(views[k], {s.wi.x, s.wi.y, -s.wi.z}) == 0.0);
    }
    // Inputs outside the domain: finite values (0 below the horizon) and failed draws, never NaN.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const Vec3& bad : {Vec3{nan, 0, 1}, Vec3{0, 0, nan}, Vec3{0, 0, -1}}) {
        const Rgb f = b.eval(bad, {0, 0, 1});
        for (int c = 0; c < 3; ++c) REQUIRE((std::isfinite(f[c]) && f[c] >= 0.0));
        if (!(bad.z > 0)) REQUIRE(f == Rgb{0, 0, 0});
        const BrdfSample s = b.sample(bad, 0.5, 0.5);
        REQUIRE((s.pdf == 0.0 || (s.wi.z > 0 && std::isfinite(s.pdf))));
    }
    for (double u : {-0.1, 1.0, nan}) REQUIRE(b.sample({0, 0, 1}, u, 0.5).pdf == 0.0);
    std::vector<Rgb> short_out(1);
    REQUIRE_THROWS_AS(b.eval(std::span(wi), std::span(wo), std::span(short_out)), ValueError);
}

inline void check_reciprocity(const Brdf& b, double rel = 1e-5) {
    const auto [wi, wo] = random_pairs(1000, 13);
    for (std::size_t k = 0; k < wi.size(); ++k) {
        INFO("reciprocity, wi " << wi[k].x << " " << wi[k].y << " " << wi[k].z << ", wo " << wo[k].x << " " << wo[k].y << " " << wo[k].z);
        check_close(b.eval(wi[k], wo[k]), b.eval(wo[k], wi[k]), rel);
    }
}

// Directional albedo at most `limit` (a source that conserves energy keeps doing so).
inline void check_furnace(const Brdf& b, double limit) {
    for (double deg : {0.0, 40.0, 70.0}) {
        const Rgb a = directional_albedo(b, deg * M_PI / 180);
        INFO("theta_o = " << deg);
        for (int c = 0; c < 3; ++c) REQUIRE(a[c] <= limit);
    }
}

// Written to a .brdfz and read back (with `load`: a table's lookup is a loading option), it evaluates
// as before.
inline void check_container_round_trip(const Brdf& b, const LoadOptions& load_options = {}) {
    TempDir dir;
    const std::string path = (dir.path / "x.brdfz").string();
    save(b, path);
    const Loaded back = load(path, load_options);
    REQUIRE(back.brdf->nbytes() == b.nbytes());
    const auto [wi, wo] = random_pairs(500, 14);
    INFO("container round trip");
    for (std::size_t k = 0; k < wi.size(); ++k) check_close(back.brdf->eval(wi[k], wo[k]), b.eval(wi[k], wo[k]), 1e-12);
}

}  // namespace brdfz::test
