#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

bool same(const rgl::Grids& a, const rgl::Grids& b) {
    return a.slices == b.slices && a.rows == b.rows && a.cols == b.cols && a.values == b.values;
}

bool same(const rgl::Tensors& a, const rgl::Tensors& b) {
    return a.theta_i == b.theta_i && same(a.ndf, b.ndf) && same(a.sigma, b.sigma) && same(a.vndf, b.vndf) &&
           same(a.luminance, b.luminance) && same(a.rgb, b.rgb) && a.jacobian == b.jacobian;
}

}  // namespace

TEST_CASE("RGL writer: derived tensors are written and read back exactly", "[rgl][writer]") {
    test::TempDir dir;
    const CoatedDiffuse material;
    rgl::WriteOptions o;
    o.n_theta_i = 6;
    o.vndf_resolution = 32;
    o.rgb_resolution = 16;
    o.ndf_resolution = 32;
    const rgl::Tensors t = rgl::derive(material, o);
    CHECK(t.theta_i.size() == 6);
    CHECK(t.rgb.rows == 16);
    CHECK(t.jacobian);

    const fs::path p = dir.path / "cd.bsdf";
    CHECK(rgl::write(p.string(), material, o) == 6u * 16 * 16);
    const rgl::ReadResult r = rgl::read(p.string());
    CHECK(same(r.brdf->tensors(), t));
    CHECK(r.description == material.describe());

    // Writing what was read gives the same file contents again.
    const fs::path q = dir.path / "again.bsdf";
    rgl::write(q.string(), *r.brdf);
    CHECK(same(rgl::read(q.string()).brdf->tensors(), t));
    CHECK_THROWS_AS(rgl::write((dir.path / "no" / "x.bsdf").string(), material, o), IoError);
    o.rgb_resolution = 1;
    CHECK_THROWS_AS(rgl::derive(material, o), ValueError);
}

TEST_CASE("RGL writer: the file reproduces the BRDF", "[rgl][writer]") {
    const CoatedDiffuse material;
    const rgl::RglBrdf written(rgl::derive(material));
    // Relative error per pair (largest channel difference over the largest channel) over random
    // pairs with θi, θo < 75°: the file reproduces f exactly at its grid points and interpolates
    // between them; the error is largest in the tails of the highlight at grazing angles (measured:
    // median 0.08%, 95th percentile 1.1%, 99th 8%).
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> rel;
    for (int k = 0; k < 4000; ++k) {
        const double ti = std::acos(1.0 - u(rng) * (1.0 - std::cos(1.3))), to = std::acos(1.0 - u(rng) * (1.0 - std::cos(1.3)));
        const double phi = u(rng) * 2.0 * M_PI;
        const Vec3 wi{std::sin(ti), 0.0, std::cos(ti)};
        const Vec3 wo{std::sin(to) * std::cos(phi), std::sin(to) * std::sin(phi), std::cos(to)};
        const Rgb a = material.eval(wi, wo), b = written.eval(wi, wo);
        double diff = 0.0, scale = 0.0;
        for (int c = 0; c < 3; ++c) {
            diff = std::max(diff, std::abs(a[c] - b[c]));
            scale = std::max(scale, a[c]);
        }
        rel.push_back(diff / scale);
    }
    std::sort(rel.begin(), rel.end());
    const double median = rel[rel.size() / 2], p95 = rel[rel.size() * 95 / 100], p99 = rel[rel.size() * 99 / 100];
    INFO("median " << median << ", 95th percentile " << p95 << ", 99th " << p99);
    CHECK(median < 0.005);
    CHECK(p95 < 0.02);
    CHECK(p99 < 0.12);
    const Metrics m = compare(material, written);
    CHECK(m.cos_rmse_rel.mean < 0.06);
}
