// The rgl_svd kind: an RGL file's own tensors, the rgb tensor a weighted low-rank product in float16 or
// int8 (brdfz/formats/rgl_svd.h).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/model.h"
#include "test_util.h"

using namespace brdfz;

namespace {

AnalyticBrdf glossy() { return AnalyticBrdf("lambert+ggx", {0.3, 0.25, 0.2, 0.6, 0.6, 0.6, 0.2, 0.04}); }

// Tensors shaped as the RGL-EPFL files' (8 θi slices, 32² rgb), from the writer (formats/rgl_writer.h);
// with `measured`, their vndf the one the ndf implies, as a measurement's is (the rgb samples then lie
// elsewhere than the writer put them: another material, as valid).
rgl::Tensors file_tensors(const Brdf& source, bool measured = true, int n_phi_i = 1) {
    rgl::WriteOptions shape;
    shape.n_theta_i = 8;
    shape.rgb_resolution = 32;
    shape.n_phi_i = n_phi_i;
    rgl::Tensors t = rgl::derive(source, shape);
    if (measured) t.vndf = rgl::derived_vndf(t.theta_i, t.ndf, t.vndf.rows, t.vndf.cols);
    return t;
}

MetricOptions over_directions() {
    MetricOptions m;
    m.over = Over::Directions;
    m.directions = 1 << 16;
    return m;
}

}  // namespace

TEST_CASE("rgl_svd: the file's tensors in float16 factors, closer with rank, exact bytes", "[rgl_svd][rgl]") {
    const rgl::RglBrdf file(file_tensors(glossy()));
    double previous = 1e9;
    for (int rank : {1, 8, 96}) {
        const Compressed c = compress(file, "rgl_svd:rank=" + std::to_string(rank));
        const auto& m = dynamic_cast<const rgl::RglBrdf&>(*c.brdf);
        REQUIRE(m.svd());
        // theta_i in float32; one row of ndf and sigma (the rows of an isotropic file's are the same);
        // the rgb factors: (8 slices · 32 columns + 3 channels · 32 rows) · rank.
        CHECK(m.nbytes() == 8 * 4 + 2 * (128 + 128) + 2 * (8 * 32 + 3 * 32) * static_cast<std::size_t>(rank));
        CHECK(m.describe().rfind("rgl_svd rank " + std::to_string(rank), 0) == 0);
        const double error = compare(file, m, over_directions()).cos_rmse_rel.mean;
        INFO("rank " << rank << ": " << error);
        CHECK(error < previous);
        previous = error;
    }
    // Full rank: what is left is float16's rounding and vndf derived from the rounded ndf.
    CHECK(previous < 2e-3);
}

TEST_CASE("rgl_svd: int8 factors, a step per block of 32 codes, exact bytes, near float16's error", "[rgl_svd][rgl]") {
    const rgl::RglBrdf file(file_tensors(glossy()));
    double previous = 1e9;
    for (int rank : {1, 4, 8, 16}) {
        const std::string r = std::to_string(rank);
        const Compressed c = compress(file, "rgl_svd:rank=" + r + ",dtype=i8");
        const auto& m = dynamic_cast<const rgl::RglBrdf&>(*c.brdf);
        REQUIRE(m.svd());
        CHECK(m.svd()->dtype == rgl::SvdDtype::I8);
        CHECK(m.describe().rfind("rgl_svd rank " + r + " (int8)", 0) == 0);
        // The codes, and a float16 step per slice and per channel in each factor.
        CHECK(m.nbytes() == 8 * 4 + 2 * (128 + 128) + (8 * 32 + 3 * 32 + 2 * (8 + 3)) * static_cast<std::size_t>(rank));
        const double error = compare(file, m, over_directions()).cos_rmse_rel.mean;
        const double f16 = compare(file, *compress(file, "rgl_svd:rank=" + r).brdf, over_directions()).cos_rmse_rel.mean;
        INFO("rank " << rank << ": int8 " << error << ", float16 " << f16);
        CHECK(error < previous);
        CHECK(error < 1.25 * f16 + 5e-3);
        previous = error;
    }
    // The rounding of the codes bounds it, not the rank.
    CHECK(previous < 6e-3);
}

TEST_CASE("rgl_svd: round trip through .brdfz, the stored bytes alone", "[rgl_svd][rgl][container]") {
    const rgl::RglBrdf file(file_tensors(glossy()));
    for (const char* spec : {"rgl_svd:rank=6,weight=0.5", "rgl_svd:rank=6,dtype=i8"}) {
        INFO(spec);
        const Compressed c = compress(file, spec);
        test::TempDir dir;
        const std::string path = (dir.path / "m.brdfz").string();
        save(*c.brdf, path);
        const Loaded back = load(path);
        const auto& m = dynamic_cast<const rgl::RglBrdf&>(*back.brdf);
        REQUIRE(m.svd());
        CHECK(m.nbytes() == c.brdf->nbytes());
        CHECK(std::filesystem::file_size(path) < 4 * c.brdf->nbytes() + 16384);  // not the expanded tensors
        // The floor per channel (and int8 factors) need a reader of the version that added them.
        CHECK(container::read(path).meta.min_reader_version == 9u);
        for (double t = 0.05; t < 1.5; t += 0.1) {
            const Vec3 wi{std::sin(t), 0.0, std::cos(t)}, wo{-0.6 * std::sin(t), 0.3, std::sqrt(1 - 0.45 * std::sin(t) * std::sin(t))};
            const Rgb a = c.brdf->eval(wi, wo), b = m.eval(wi, wo);
            CHECK(a == b);
        }
    }
}

TEST_CASE("rgl_svd: the product is not below the source's least value per channel", "[rgl_svd][rgl][container]") {
    const rgl::RglBrdf file(file_tensors(glossy()));
    rgl::SvdTensors s = rgl::factor(file.tensors(), 2, 1.0, rgl::SvdDtype::I8);
    const std::size_t plane = s.rows * s.cols;
    for (std::size_t c = 0; c < 3; ++c) {
        float least = 1e30f;
        for (std::size_t i = 0; i < s.slices; ++i)
            for (std::size_t p = 0; p < plane; ++p) least = std::min(least, file.tensors().rgb.values[(i * 3 + c) * plane + p]);
        CHECK(s.floor[c] == least);
    }
    const auto below = [&](const rgl::Tensors& t) {
        std::size_t n = 0;
        for (std::size_t i = 0; i < t.rgb.values.size(); ++i) n += t.rgb.values[i] < s.floor[(i / plane) % 3];
        return n;
    };
    CHECK(below(rgl::expand(s)) == 0);
    // Without it (as a file of container version 8 is read) rank 2 undershoots.
    rgl::SvdTensors unfloored = s;
    unfloored.floor.fill(-std::numeric_limits<float>::infinity());
    CHECK(below(rgl::expand(unfloored)) > 0);
    // Such a file needs only version 8, and reads back unclamped.
    test::TempDir dir;
    const std::string path = (dir.path / "v8.brdfz").string();
    unfloored = rgl::factor(file.tensors(), 2, 1.0);
    unfloored.floor.fill(-std::numeric_limits<float>::infinity());
    save(*rgl::make_svd_brdf(unfloored), path);
    CHECK(container::read(path).meta.min_reader_version == 8u);
    const Loaded loaded = load(path);
    CHECK(dynamic_cast<const rgl::RglBrdf&>(*loaded.brdf).tensors().rgb.values == rgl::expand(unfloored).rgb.values);
    s.floor[1] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("floor"));
}

TEST_CASE("rgl_svd: sources and settings it cannot take are refused with a reason", "[rgl_svd][rgl]") {
    const rgl::RglBrdf file(file_tensors(glossy()));
    CHECK_THROWS_WITH(compress(glossy(), "rgl_svd:rank=4"), Catch::Contains("must be an isotropic RGL-EPFL"));
    CHECK_THROWS_AS(compress(file, "rgl_svd:rank=0"), SpecError);
    CHECK_THROWS_AS(compress(file, "rgl_svd:rank=97"), SpecError);
    rgl::WriteOptions small;
    small.n_theta_i = 2;
    small.rgb_resolution = 4;
    rgl::Tensors coarse = rgl::derive(glossy(), small);
    coarse.vndf = rgl::derived_vndf(coarse.theta_i, coarse.ndf, coarse.vndf.rows, coarse.vndf.cols);
    CHECK_THROWS_WITH(compress(rgl::RglBrdf(std::move(coarse)), "rgl_svd:rank=9"), Catch::Contains("rank must be in [1, 8]"));
    CHECK_THROWS_WITH(compress(file, "rgl_svd:weight=-1"), Catch::Contains("weight must be in [0, 4]"));
    // Its own output is not factored again.
    CHECK_THROWS_WITH(compress(*compress(file, "rgl_svd:rank=2").brdf, "rgl_svd:rank=2"), Catch::Contains("RGL-EPFL"));
    const rgl::RglBrdf aniso(file_tensors(glossy(), false, 3));
    CHECK_THROWS_WITH(compress(aniso, "rgl_svd:rank=2"), Catch::Contains("isotropic"));
    // A file whose rgb samples lie where a vndf of its own puts them (brdfz's writer's).
    const rgl::Tensors written = file_tensors(glossy(), false);
    CHECK_FALSE(rgl::vndf_is_derived(written));
    CHECK_THROWS_WITH(compress(rgl::RglBrdf(rgl::Tensors(written)), "rgl_svd:rank=2"), Catch::Contains("vndf derived from its ndf"));
    CHECK_THROWS_WITH(rgl::factor(written, 2, 1.0), Catch::Contains("not the one its ndf implies"));
    // Stored forms whose shapes disagree.
    rgl::SvdTensors s = rgl::factor(file.tensors(), 2, 1.0);
    s.v.pop_back();
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("inconsistent"));
    s = rgl::factor(file.tensors(), 2, 1.0);
    s.slices = s.theta_i.size() + 1;
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("inconsistent"));
    CHECK_THROWS_AS(compress(file, "rgl_svd:dtype=f32"), SpecError);
    s = rgl::factor(file.tensors(), 2, 1.0, rgl::SvdDtype::I8);
    s.v_scale.pop_back();
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("inconsistent"));
    s = rgl::factor(file.tensors(), 2, 1.0, rgl::SvdDtype::I8);
    s.u_scale[0] = 0x7C00;  // +infinity
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("step"));
    s = rgl::factor(file.tensors(), 2, 1.0, rgl::SvdDtype::I8);
    s.u = {1};  // float16 factors beside the int8 ones
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("inconsistent"));
    s = rgl::factor(file.tensors(), 2, 1.0, rgl::SvdDtype::I8);
    s.v_scale_exponent = 200;  // steps beyond float's range
    CHECK_THROWS_WITH(rgl::expand(s), Catch::Contains("beyond"));
}

namespace {

// A shared RGL file, or nothing (with a warning) where ../shared is missing.
std::optional<Loaded> shared_file(const char* name) {
    const std::filesystem::path path = test::rgl_file(name);
    if (!std::filesystem::exists(path)) {
        WARN("skipped: " << path << " is missing (../shared/data)");
        return std::nullopt;
    }
    return load(path.string());
}

// `spec` of the file within `max_bytes` and 2 % over directions, and less than half the error of the svd
// setting of about its size.
void check_against_svd(const Loaded& file, const std::string& spec, std::size_t max_bytes, const std::string& svd_spec) {
    MetricOptions m;
    m.over = Over::Directions;
    const Compressed c = compress(*file.brdf, spec);
    CHECK(c.brdf->nbytes() <= max_bytes);
    const double error = compare(*file.brdf, *c.brdf, m).cos_rmse_rel.mean;
    const double svd = compare(*file.brdf, *compress(*file.brdf, svd_spec).brdf, m).cos_rmse_rel.mean;
    INFO(spec << ", " << c.brdf->nbytes() << " B: " << error << ", the svd " << svd);
    CHECK(error < 0.02);
    CHECK(svd > 2 * error);
}

}  // namespace

TEST_CASE("rgl_svd holds chm_mint's sharp peak within 2 % over directions at 16 KB", "[rgl_svd][rgl]") {
    const std::optional<Loaded> loaded = shared_file("chm_mint");
    if (!loaded) return;
    // The vndf and luminance tensors it derives are the file's own (D·cos of ndf; Y of rgb), to float16's rounding.
    const rgl::Tensors& t = dynamic_cast<const rgl::RglBrdf&>(*loaded->brdf).tensors();
    CHECK(rgl::vndf_is_derived(t));
    const rgl::Tensors e = rgl::expand(rgl::factor(t, 96, 1.0));
    REQUIRE(e.luminance.values.size() == t.luminance.values.size());
    float top = 0, worst = 0;
    for (std::size_t i = 0; i < t.luminance.values.size(); ++i)
        top = std::max(top, std::abs(t.luminance.values[i])), worst = std::max(worst, std::abs(e.luminance.values[i] - t.luminance.values[i]));
    CHECK(worst < 2e-3f * top);
    // The best svd at that size is near 5 %.
    check_against_svd(*loaded, "rgl_svd:rank=22", 16384,
                      "svd:rank=14,space=cos,colour=shared,res=128x28x12,dwarp=0.9,symmetry=bilateral,dtype=f16");
}

TEST_CASE("rgl_svd in int8 holds leaf_maple within 2 % over directions in 4 KB", "[rgl_svd][rgl]") {
    const std::optional<Loaded> loaded = shared_file("leaf_maple");
    if (!loaded) return;
    // The svd candidate of that size (3,888 B).
    check_against_svd(*loaded, "rgl_svd:rank=9,dtype=i8", 4000,
                      "svd:rank=6,space=cos,colour=shared,res=32x22x13,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16");
}
