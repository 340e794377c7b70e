// RglBrdf's batch kernels (formats/rgl/kernels.cpp) against their scalar reference (formats/rgl/
// reference.h: libm's asin, atan2, sin and cos; std::lower_bound; one pair at a time), and against
// themselves: one call = batch, in every SIMD build, and the builds alike.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/formats/rgl.h"
#include "rgl/reference.h"
#include "sample_stats.h"
#include "simd_levels.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

// The kernels' angles come from a polynomial arctangent (6e-11 relative) and a sine table (a few ulp)
// where the scalar path called libm: what they may change in f, pdf and the weights (relative, with the
// floors of check_against_scalar) and in a sampled direction (rgl.h). On the shared files the worst seen
// is a third of these.
constexpr double kRel = 1e-8, kDir = 1e-8;

std::vector<fs::path> rgl_files() {
    std::vector<fs::path> files;
    const fs::path dir = fs::path(BRDFZ_SHARED_DIR) / "data" / "rgl";
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return files;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".bsdf") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

// Pairs uniform on the upper hemisphere, then the awkward ones: at the pole, along the axes (azimuth
// ±π, signed zeros), grazing, and wi = wo.
struct Inputs {
    std::vector<Vec3> wi, wo;
    std::vector<std::array<double, 2>> u;
};
Inputs inputs(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const auto upper = [&] {
        const double z = u01(rng), r = std::sqrt(1 - z * z), phi = 2 * std::numbers::pi * u01(rng);
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    Inputs in;
    for (std::size_t k = 0; k < n; ++k) {
        in.wi.push_back(upper());
        in.wo.push_back(upper());
        in.u.push_back({u01(rng), u01(rng)});
    }
    const std::vector<Vec3> special = {{0, 0, 1},          {-0.0, 0, 1},          {0, -0.0, 1},       {-0.0, -0.0, 1},
                                       {-0.6, 0, 0.8},     {-0.6, -0.0, 0.8},     {0.6, 0, 0.8},      {0, 0.6, 0.8},
                                       {0.9999, 0, 0.01414}, {0, -1, 1e-9},      {1e-9, 1e-9, 1},    {-0.8, 0.6, 1e-300}};
    for (const Vec3& a : special)
        for (const Vec3& b : special) {
            in.wi.push_back(normalize(a));
            in.wo.push_back(normalize(b));
            in.u.push_back({u01(rng), u01(rng)});
        }
    return in;
}

using test::same_bits;

// The batch kernels against the scalar path on n random pairs and the awkward ones.
void check_against_scalar(const rgl::RglBrdf& b, std::size_t n) {
    const rgl::detail::Reference model(b);
    const Inputs in = inputs(n, 20261201);
    const std::size_t m = in.wi.size();
    std::vector<Rgb> f(m);
    std::vector<double> p(m);
    std::vector<BrdfSample> s(m);
    b.eval(in.wi, in.wo, f);
    b.pdf(in.wo, in.wi, p);
    b.sample(in.wo, in.u, s);
    // f relative to the pair's largest channel, or to 1e-4 of the batch's largest value where that is
    // larger: values near 0 come from blends of larger ones (of both signs, in real files), whose
    // rounding they inherit. Densities and weights likewise, relative to their own value or to 1e-4 of
    // the batch's largest density.
    std::vector<Rgb> g(m);
    std::vector<double> q(m);
    std::vector<BrdfSample> t(m);
    double f_top = 0, p_top = 0;
    for (std::size_t k = 0; k < m; ++k) {
        g[k] = model.eval(in.wi[k], in.wo[k]);
        q[k] = model.pdf(in.wo[k], in.wi[k]);
        t[k] = model.sample(in.wo[k], in.u[k][0], in.u[k][1]);
        for (double v : g[k]) f_top = std::max(f_top, std::fabs(v));
        p_top = std::max({p_top, q[k], t[k].pdf});
    }
    const auto rel = [](double a, double b, double floor) { return std::fabs(a - b) / std::max(std::fabs(b), floor); };
    double worst_f = 0, worst_p = 0, worst_w = 0, worst_dir = 0;
    std::size_t mismatched = 0;  // a draw that failed in one and not in the other
    for (std::size_t k = 0; k < m; ++k) {
        const double scale = std::max({std::fabs(g[k][0]), std::fabs(g[k][1]), std::fabs(g[k][2]), 1e-4 * f_top});
        for (int c = 0; c < 3; ++c) worst_f = std::max(worst_f, scale > 0 ? std::fabs(f[k][c] - g[k][c]) / scale : 0.0);
        worst_p = std::max(worst_p, rel(p[k], q[k], 1e-4 * p_top));
        mismatched += (s[k].pdf > 0) != (t[k].pdf > 0);
        if (s[k].pdf > 0 && t[k].pdf > 0) {
            worst_dir = std::max(worst_dir, length(s[k].wi - t[k].wi));
            worst_p = std::max(worst_p, rel(s[k].pdf, t[k].pdf, 1e-4 * p_top));
            // The weight f·cosθi/pdf, its f floored as above.
            const double w = std::max({std::fabs(t[k].weight[0]), std::fabs(t[k].weight[1]), std::fabs(t[k].weight[2]),
                                       1e-4 * f_top * t[k].wi.z / t[k].pdf});
            for (int c = 0; c < 3; ++c)
                worst_w = std::max(worst_w, w > 0 ? std::fabs(s[k].weight[c] - t[k].weight[c]) / w : 0.0);
        }
    }
    INFO("worst: f " << worst_f << ", pdf " << worst_p << ", weight " << worst_w << ", direction " << worst_dir);
    CHECK(worst_f <= kRel);
    CHECK(worst_p <= kRel);
    CHECK(worst_w <= kRel);
    CHECK(worst_dir <= kDir);
    CHECK(mismatched == 0);
}

}  // namespace

namespace {

// Tensors of random positive tables on small grids (rows ≠ cols) at `n_theta` elevations.
rgl::Tensors random_tensors(int n_theta, std::uint64_t seed, bool luminance) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0.05f, 1.0f);
    const auto grids = [&](std::size_t slices, std::size_t rows, std::size_t cols) {
        rgl::Grids g{slices, rows, cols, std::vector<float>(slices * rows * cols)};
        for (float& v : g.values) v = u(rng);
        return g;
    };
    rgl::Tensors t;
    for (int k = 0; k < n_theta; ++k) t.theta_i.push_back(static_cast<float>(1.5 * (k + 0.3) / n_theta));
    const auto slices = static_cast<std::size_t>(n_theta);
    t.ndf = grids(1, 3, 9);
    t.sigma = grids(1, 2, 7);
    t.vndf = grids(slices, 11, 13);
    t.rgb = grids(3 * slices, 5, 6);
    if (luminance) t.luminance = grids(slices, 5, 6);
    return t;
}

void check_random_tensors(std::size_t n) {
    for (const auto& [n_theta, lum] : {std::pair{1, true}, std::pair{3, true}, std::pair{4, false}}) {
        INFO(n_theta << " slices" << (lum ? "" : ", no luminance"));
        const rgl::RglBrdf b(random_tensors(n_theta, 17 + n_theta, lum));
        check_against_scalar(b, n);
    }
}

}  // namespace

TEST_CASE("rgl kernels: eval, pdf and sample within 1e-8 of the scalar path", "[rgl][kernels][light][qemu]") {
    check_random_tensors(20000);
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    for (std::size_t i = 0; i < files.size(); i += 5) check_against_scalar(*rgl::read(files[i].string()).brdf, 20000);
}

TEST_CASE("rgl kernels: eval, pdf and sample within 1e-8 of the scalar path on every shared file",
          "[rgl][kernels][heavy]") {
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped: ../shared/data/rgl missing");
        return;
    }
    for (const auto& path : files) {
        INFO(path.filename().string());
        check_against_scalar(*rgl::read(path.string()).brdf, 200000);
    }
}

namespace {

// One call at a time against the batch, and each SIMD build against the narrowest, bit for bit.
void check_builds(const rgl::RglBrdf& b, std::size_t n) {
    const Inputs in = inputs(n, 7);
    const std::size_t m = in.wi.size();
    std::vector<Rgb> f0(m), f(m);
    std::vector<double> p0(m), p(m);
    std::vector<BrdfSample> s0(m), s(m);
    bool first = true;
    for (detail::Simd level : test::simd_levels()) {
        INFO(test::simd_label(level) << " build");
        const test::SimdCap cap(level);
        b.eval(in.wi, in.wo, f);
        b.pdf(in.wo, in.wi, p);
        b.sample(in.wo, in.u, s);
        std::size_t differ = 0;
        for (std::size_t k = 0; k < m; ++k) {
            const Rgb one = b.eval(in.wi[k], in.wo[k]);
            for (int c = 0; c < 3; ++c) differ += !same_bits(one[c], f[k][c]);
            differ += !same_bits(b.pdf(in.wo[k], in.wi[k]), p[k]);
            differ += !same_bits(b.sample(in.wo[k], in.u[k][0], in.u[k][1]), s[k]);
            if (!first) {
                for (int c = 0; c < 3; ++c) differ += !same_bits(f0[k][c], f[k][c]);
                differ += !same_bits(p0[k], p[k]) + !same_bits(s0[k], s[k]);
            }
        }
        CHECK(differ == 0);
        if (first) f0 = f, p0 = p, s0 = s, first = false;
    }
}

}  // namespace

TEST_CASE("rgl kernels: one call = batch, bit for bit, and every SIMD build gives the same bits",
          "[rgl][kernels][qemu]") {
    if (test::simd_levels().size() < 2) WARN("this CPU has only the baseline build");
    for (int n_theta : {1, 3}) check_builds(rgl::RglBrdf(random_tensors(n_theta, 5, true)), 3000);
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    check_builds(*rgl::read(files.front().string()).brdf, 20000);
}

TEST_CASE("rgl kernels: the batch sampler's chi-square on random tables and a shared file, and batch = one call",
          "[rgl][kernels][sample]") {
    for (int n_theta : {1, 3}) {
        INFO(n_theta << " slices (random tables)");
        test::check_batch_sampler(rgl::RglBrdf(random_tensors(n_theta, 9, true)), 100000);
    }
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    // One file: rgl_test.cpp's sampler test takes every file at more draws.
    INFO(files.front().filename().string());
    test::check_batch_sampler(*rgl::read(files.front().string()).brdf, 50000);
}

// The batch sampler's χ² on every shared file is rgl_test.cpp's sampler test (its draws are batches).
TEST_CASE("rgl kernels: batch sample, pdf and eval are one call's bits on every shared file",
          "[rgl][kernels][sample][qemu]") {
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped: ../shared/data/rgl missing");
        return;
    }
    for (const auto& path : files) {
        INFO(path.filename().string());
        test::check_batch_bits(*rgl::read(path.string()).brdf);
    }
}
