// Stored payloads in valid envelopes: every checksum right, the values hostile (Inf, NaN, negatives,
// 3e38). Each is refused at load with a reason, or loads and evaluates to finite values >= 0.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/exr.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "robustness/envelope.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string load_error(const fs::path& p) {
    try {
        load(p.string());
    } catch (const FormatError& e) {
        return e.what();
    }
    return "loaded";
}

// Finite and >= 0 at pairs over the hemisphere, pdf finite and >= 0: what a loaded file must give.
void check_evaluates(const Brdf& b, bool non_negative = true) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const auto dir = [&] {
        const double z = u(rng), phi = 6.283185307179586 * u(rng), r = std::sqrt(1.0 - z * z);
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    for (int k = 0; k < 500; ++k) {
        const Vec3 wi = dir(), wo = dir();
        const Rgb f = b.eval(wi, wo);
        for (double c : f) {
            REQUIRE(std::isfinite(c));
            if (non_negative) REQUIRE(c >= 0.0);
        }
        const double p = b.pdf(wo, wi);
        REQUIRE((std::isfinite(p) && p >= 0.0));
    }
}

// 2x3x4 bins of plausible values.
std::vector<float> plausible(std::size_t bins) {
    std::vector<float> v(3 * bins);
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = 0.1f + 0.01f * static_cast<float>(k % 7);
    return v;
}

}  // namespace

TEST_CASE("robustness: float32 table payloads: +Inf, negatives and all-NaN are refused", "[robustness][container]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "t.brdfz";
    std::vector<float> v = plausible(24);
    v[5] = kNaN;  // an unmeasured entry is what NaN means: it loads
    test::write_float32_table(p.string(), 2, 3, 4, v);
    REQUIRE(load_error(p) == "loaded");
    check_evaluates(*load(p.string()).brdf);

    v[7] = kInf;
    test::write_float32_table(p.string(), 2, 3, 4, v);
    CHECK_THAT(load_error(p), Catch::Contains("1 infinite and 0 negative values"));
    v[7] = -kInf;
    test::write_float32_table(p.string(), 2, 3, 4, v);
    CHECK_THAT(load_error(p), Catch::Contains("1 infinite"));
    v[7] = -0.5f;
    test::write_float32_table(p.string(), 2, 3, 4, v);
    CHECK_THAT(load_error(p), Catch::Contains("0 infinite and 1 negative values"));
    test::write_float32_table(p.string(), 2, 3, 4, std::vector<float>(72, kNaN));
    CHECK_THAT(load_error(p), Catch::Contains("holds no value (every entry is NaN)"));
    std::vector<float> one(72, kNaN);
    one[40] = 0.25f;  // a single value: a table, if a poor one
    test::write_float32_table(p.string(), 2, 3, 4, one);
    REQUIRE(load_error(p) == "loaded");
    test::write_float32_table(p.string(), 2, 3, 4, std::vector<float>(72, 3e38f));  // large but finite: a value
    REQUIRE(load_error(p) == "loaded");
    check_evaluates(*load(p.string()).brdf);
}

TEST_CASE("robustness: a container whose units, cosine or conventions say otherwise is refused, naming them",
          "[robustness][container]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "t.brdfz";
    const std::vector<float> values = plausible(2 * 3 * 4);
    test::write_float32_table(p.string(), 2, 3, 4, values);
    REQUIRE(load_error(p) == "loaded");
    struct Case {
        std::function<void(test::Meaning&)> change;
        std::string message;
    };
    const std::vector<Case> cases{
        {[](test::Meaning& m) { m.units = "W/(m^2 sr)"; }, "attribute 'units' is \"W/(m^2 sr)\"; this brdfz reads only \"1/sr\""},
        {[](test::Meaning& m) { m.cosine = "included"; }, "attribute 'cosine' is \"included\"; this brdfz reads only \"excluded\""},
        {[](test::Meaning& m) { m.conventions = "normal +y"; }, "attribute 'conventions' is \"normal +y\""},
    };
    for (const Case& c : cases) {
        test::Meaning meaning;
        c.change(meaning);
        test::write_float32_table(p.string(), 2, 3, 4, values, meaning);
        INFO(c.message);
        CHECK_THROWS_AS(load(p.string()), UnsupportedError);
        CHECK_THROWS_WITH(load(p.string()), Catch::StartsWith(p.string() + ": " + c.message));
        CHECK_THROWS_WITH(container::read_metadata(p.string()), Catch::Contains(c.message));
    }
}

TEST_CASE("robustness: compact tables without a value are refused", "[robustness][container][compact]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "c.brdfz";
    const GridSpec g{2, 3, 4};
    std::vector<std::uint8_t> half(2 * 3 * g.bins());
    for (std::size_t i = 0; i < 3 * g.bins(); ++i) std::memcpy(half.data() + 2 * i, &CompactTable::kInvalidF16, 2);
    container::write(p.string(), CompactTableBrdf(CompactTable(g, TableDtype::F16, half, {}), Lookup::Linear));
    CHECK_THAT(load_error(p), Catch::Contains("holds no value"));
    std::array<ChannelCodec, 3> codecs;
    for (ChannelCodec& c : codecs) c = {1.0, 0.0, 0.01};
    container::write(p.string(), CompactTableBrdf(CompactTable(g, TableDtype::U8Log,
                                                               std::vector<std::uint8_t>(3 * g.bins(), 255), codecs),
                                                  Lookup::Linear));
    CHECK_THAT(load_error(p), Catch::Contains("holds no value"));
}

TEST_CASE("robustness: factors that would overflow (3e38) are refused, large sane ones load", "[robustness][container][factored]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "f.brdfz";
    std::vector<float> u(2 * 3, 0.5f), v(3 * 4 * 3, 0.5f);
    test::write_factors(p.string(), 2, 3, 4, u, v);
    REQUIRE(load_error(p) == "loaded");
    check_evaluates(*load(p.string()).brdf);

    u[1] = 3e38f;
    test::write_factors(p.string(), 2, 3, 4, u, v);
    CHECK_THAT(load_error(p), Catch::Contains("beyond the float range"));
    u[1] = 3e38f, v[4] = -3e38f;  // Inf − Inf in a kernel's sum: NaN
    test::write_factors(p.string(), 2, 3, 4, u, v);
    CHECK_THAT(load_error(p), Catch::Contains("beyond the float range"));
    u[1] = kNaN;
    test::write_factors(p.string(), 2, 3, 4, u, v);
    CHECK_THAT(load_error(p), Catch::Contains("not finite"));

    // The same rule in the library, for factors built in memory.
    Factors f;
    f.grid = {2, 3, 4};
    f.u = std::vector<float>(6, 1e20f);
    f.v = std::vector<float>(36, 1e20f);
    CHECK_THROWS_WITH(FactoredBrdf(f), Catch::Contains("beyond the float range"));
}

TEST_CASE("robustness: PCA coefficients that reconstruct beyond the float range are refused", "[robustness][container][pca]") {
    const test::TempDir dir;
    const GridSpec g{8, 8, 16};
    std::vector<Table> tables;
    for (double alpha : {0.1, 0.2, 0.4}) {
        TabulateOptions o;
        o.grid = g;
        tables.push_back(tabulate(AnalyticBrdf("lambert+ggx", {0.3, 0.4, 0.5, 0.5, 0.5, 0.5, alpha, 0.04}), o).table);
    }
    const std::vector<const Table*> ptrs{&tables[0], &tables[1], &tables[2]};
    PcaTrainOptions o;
    o.k_max = 2;
    const auto basis = std::make_shared<const PcaBasis>(train_pca_basis(ptrs, o));
    const fs::path p = dir.path / "p.brdfz";
    container::write(p.string(), PcaBrdf(basis, basis->project(tables[1], 2), Lookup::Linear,
                                         PcaBrdf::BasisStorage::Embedded));
    REQUIRE(load_error(p) == "loaded");
    check_evaluates(*load(p.string()).brdf);
    for (const std::vector<float>& c : {std::vector<float>{3e38f, -3e38f}, std::vector<float>{1e6f, 0.0f}}) {
        container::write(p.string(), PcaBrdf(basis, c, Lookup::Linear, PcaBrdf::BasisStorage::Embedded));
        CHECK_THAT(load_error(p), Catch::Contains("beyond the float range"));
    }
}

TEST_CASE("robustness: PCA bases with values that are not finite, or negative medians, are refused at load",
          "[robustness][container][pca]") {
    const test::TempDir dir;
    const GridSpec g{4, 4, 8};
    std::vector<Table> tables;
    for (double alpha : {0.1, 0.2, 0.4}) {
        TabulateOptions o;
        o.grid = g;
        tables.push_back(tabulate(AnalyticBrdf("lambert+ggx", {0.3, 0.4, 0.5, 0.5, 0.5, 0.5, alpha, 0.04}), o).table);
    }
    PcaTrainOptions o;
    o.k_max = 2;
    const std::vector<const Table*> ptrs{&tables[0], &tables[1], &tables[2]};
    const PcaBasis basis = train_pca_basis(ptrs, o);
    test::PcaParts good{4, 4, 8, basis.epsilon(), {basis.median().begin(), basis.median().end()},
                        {basis.mean().begin(), basis.mean().end()},
                        {basis.components().begin(), basis.components().end()}, {},
                        {basis.variances().begin(), basis.variances().end()}};
    const auto shared = std::make_shared<const PcaBasis>(basis);
    good.coefficients = shared->project(tables[1], 2);
    const fs::path p = dir.path / "p.brdfz";
    // The envelope itself is valid: the same parts load and evaluate as the library's own file does.
    test::write_pca(p.string(), good);
    REQUIRE(load_error(p) == "loaded");
    const auto loaded = load(p.string()).brdf;
    check_evaluates(*loaded);
    const PcaBrdf direct(shared, good.coefficients, Lookup::Linear, PcaBrdf::BasisStorage::Embedded);
    const Vec3 wi = normalize(Vec3{0.3, 0.1, 0.9}), wo = normalize(Vec3{-0.2, 0.4, 0.8});
    CHECK(loaded->eval(wi, wo)[1] == Approx(direct.eval(wi, wo)[1]).epsilon(1e-6));

    std::size_t kept = 0;  // a bin the basis keeps (its median is a number)
    while (std::isnan(good.median[3 * kept])) ++kept;
    struct Case {
        const char* what;
        std::function<void(test::PcaParts&)> spoil;
        const char* message;
    };
    const std::vector<Case> cases{
        {"mean +Inf", [](test::PcaParts& q) { q.mean[5] = kInf; }, "the mean has a value that is not finite"},
        {"mean NaN", [](test::PcaParts& q) { q.mean[0] = kNaN; }, "the mean has a value that is not finite"},
        {"component -Inf", [](test::PcaParts& q) { q.components[7] = -kInf; }, "a component has a value that is not finite"},
        {"variance NaN", [](test::PcaParts& q) { q.variances[1] = std::nan(""); }, "variance is not finite and >= 0"},
        {"variance < 0", [](test::PcaParts& q) { q.variances[0] = -1.0; }, "variance is not finite and >= 0"},
        {"median < 0", [&](test::PcaParts& q) { q.median[3 * kept + 1] = -0.5f; }, "has a median that is not finite and >= 0"},
        {"median +Inf", [&](test::PcaParts& q) { q.median[3 * kept] = kInf; }, "has a median that is not finite and >= 0"},
        {"components 3e38", [](test::PcaParts& q) { std::fill(q.components.begin(), q.components.end(), 3e38f); },
         "beyond the float range"},
        {"epsilon 0", [](test::PcaParts& q) { q.epsilon = 0.0; }, "epsilon"},
    };
    for (const Case& c : cases) {
        INFO(c.what);
        test::PcaParts bad = good;
        c.spoil(bad);
        test::write_pca(p.string(), bad);
        CHECK_THAT(load_error(p), Catch::Contains(c.message));
    }
}

TEST_CASE("robustness: analytic parameters outside their bounds are refused, at the bounds they evaluate",
          "[robustness][container][analytic]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "a.brdfz";
    const Model m = Model::parse("lambert+ggx");
    std::vector<std::string> names;
    std::vector<double> lo, hi;
    for (std::size_t k = 0; k < m.size(); ++k) {
        names.push_back(m.name(k));
        lo.push_back(m.spec(k).lo);
        hi.push_back(m.spec(k).hi);
    }
    for (const std::vector<double>* params : {&lo, &hi}) {
        test::write_analytic(p.string(), "lambert+ggx", names, *params);
        REQUIRE(load_error(p) == "loaded");
        check_evaluates(*load(p.string()).brdf);
    }
    for (double bad : {3e38, -1.0, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
        std::vector<double> params = hi;
        params[0] = bad;
        test::write_analytic(p.string(), "lambert+ggx", names, params);
        CHECK_THAT(load_error(p), Catch::Contains("parameter"));
    }
}

namespace {

// Small RGL tensors that Mitsuba renders: constant densities, colours 0.1, 0.2, 0.3.
rgl::Tensors tensors() {
    rgl::Tensors t;
    t.theta_i = {0.0f, 0.8f, 1.5f};
    const auto grids = [](std::size_t slices, float v) {
        rgl::Grids g;
        g.slices = slices;
        g.rows = g.cols = 4;
        g.values.assign(slices * 16, v);
        return g;
    };
    t.ndf = grids(1, 1.0f);
    t.sigma = grids(1, 1.0f);
    t.vndf = grids(3, 1.0f);
    t.luminance = grids(3, 1.0f);
    t.rgb = grids(9, 0.2f);
    return t;
}

// The tensors written as .bsdf (the RGL writer) and as .brdfz (the container): both readers apply
// the same rules.
std::vector<fs::path> written(const test::TempDir& dir, const rgl::Tensors& t) {
    const rgl::RglBrdf b(t);
    const fs::path bsdf = dir.path / "r.bsdf", brdfz = dir.path / "r.brdfz";
    rgl::write(bsdf.string(), b);
    container::write(brdfz.string(), b);
    return {bsdf, brdfz};
}

}  // namespace

TEST_CASE("robustness: RGL fields Mitsuba cannot render are refused in .bsdf and .brdfz, per field",
          "[robustness][rgl]") {
    const test::TempDir dir;
    for (const fs::path& p : written(dir, tensors())) REQUIRE(load_error(p) == "loaded");

    const auto refused = [&](rgl::Tensors t, const char* message) {
        for (const fs::path& p : written(dir, t)) {
            INFO(p << ": " << message);
            CHECK_THAT(load_error(p), Catch::Contains(message));
        }
    };
    rgl::Tensors t = tensors();
    t.ndf.values[5] = -0.5f;
    refused(t, "field 'ndf' holds 1 negative of 16 values");
    t = tensors();
    for (float& v : t.ndf.values) v = -v;
    refused(t, "field 'ndf' holds 16 negative of 16 values");
    t = tensors();
    t.sigma.values[0] = -1.0f;
    refused(t, "field 'sigma' holds 1 negative of 16 values");
    t = tensors();
    t.sigma.values[3] = 0.0f;
    refused(t, "field 'sigma' holds 1 values of 0 (of 16)");
    t = tensors();
    for (float& v : t.rgb.values) v = -0.2f;
    refused(t, "field 'rgb' has no finite value >= 0 (144 negative, 0 NaN, 0 Inf of 144)");
    // Black renders: all-zero rgb loads (and evaluates to 0).
    t = tensors();
    for (float& v : t.rgb.values) v = 0.0f;
    for (const fs::path& p : written(dir, t)) {
        REQUIRE(load_error(p) == "loaded");
        CHECK(load(p.string()).brdf->eval({0, 0, 1}, {0.3, 0, 0.953939}) == Rgb{0, 0, 0});
    }
}

TEST_CASE("robustness: RGL luminance with negative values loads, counted, and samples", "[robustness][rgl][sample]") {
    const test::TempDir dir;
    rgl::Tensors t = tensors();
    t.luminance.values[1] = -1e-3f;
    t.luminance.values[20] = -2e-2f;
    for (const fs::path& p : written(dir, t)) {
        INFO(p);
        REQUIRE(load_error(p) == "loaded");
        check_evaluates(*load(p.string()).brdf, false);
    }
    const rgl::ReadResult r = rgl::read((dir.path / "r.bsdf").string());
    REQUIRE(r.fields.size() == 5);
    CHECK(r.fields[3].first == "luminance");
    CHECK(r.fields[3].second.negative == 2);
    CHECK(r.fields[4].first == "rgb");
    CHECK(r.fields[0].second.negative + r.fields[1].second.negative + r.fields[2].second.negative == 0);
    // The file keeps its values: written again, the luminance is the same.
    rgl::write((dir.path / "again.bsdf").string(), *r.brdf);
    CHECK(rgl::read((dir.path / "again.bsdf").string()).fields[3].second.negative == 2);
    // Sampling: pdf is the density of the draws where they land (never negative).
    for (int k = 0; k < 200; ++k) {
        const BrdfSample s = r.brdf->sample(Vec3{0.3, 0.1, 0.948683}, (k + 0.5) / 200.0, 0.37);
        CHECK((std::isfinite(s.pdf) && s.pdf >= 0.0));
    }
    // A luminance slice without positive mass: sampling falls back to the VNDF warp.
    t = tensors();
    for (std::size_t k = 0; k < 16; ++k) t.luminance.values[k] = -1.0f;
    for (const fs::path& p : written(dir, t)) {
        REQUIRE(load_error(p) == "loaded");
        check_evaluates(*load(p.string()).brdf, false);
    }
}

TEST_CASE("robustness: RGL rgb all NaN or all Inf is refused in .bsdf and .brdfz, partly, it is counted",
          "[robustness][rgl]") {
    const test::TempDir dir;
    const fs::path bsdf = dir.path / "h.bsdf", brdfz = dir.path / "h.brdfz";
    for (float hostile : {kNaN, kInf, -kInf}) {
        rgl::Tensors t = tensors();
        for (float& v : t.rgb.values) v = hostile;
        test::write_bsdf(bsdf.string(), t);
        test::write_rgl_container(brdfz.string(), t);
        for (const fs::path& p : {bsdf, brdfz}) {
            INFO(p << " " << hostile);
            CHECK_THAT(load_error(p), Catch::Contains("field 'rgb' has no finite value >= 0"));
        }
    }
    rgl::Tensors t = tensors();
    t.rgb.values[0] = kNaN;
    t.rgb.values[1] = kInf;
    t.rgb.values[2] = -0.01f;
    test::write_bsdf(bsdf.string(), t);
    const rgl::ReadResult r = rgl::read(bsdf.string());
    CHECK(r.counts.nan == 1);
    CHECK(r.counts.inf == 1);
    CHECK(r.counts.negative == 1);
    check_evaluates(*r.brdf, false);
    // Non-finite densities: refused by either reader, naming the field.
    t = tensors();
    t.vndf.values[4] = kNaN;
    test::write_bsdf(bsdf.string(), t);
    test::write_rgl_container(brdfz.string(), t);
    for (const fs::path& p : {bsdf, brdfz}) CHECK_THAT(load_error(p), Catch::Contains("field 'vndf' holds 1 NaN of 48 values"));
    t = tensors();
    t.vndf.values[4] = -0.25f;
    test::write_bsdf(bsdf.string(), t);
    CHECK_THAT(load_error(bsdf), Catch::Contains("field 'vndf' holds 1 negative of 48 values"));
}

TEST_CASE("robustness: EXR tables: negative and infinite channels are invalid and counted, none valid is refused",
          "[robustness][exr]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "t.exr";
    Table t(GridSpec{2, 3, 4});
    for (std::size_t b = 0; b < t.bins(); ++b) t.set(b, {0.2, 0.3, 0.4});
    t.data()[0] = kInf;
    t.data()[4] = -0.5f;
    t.data()[8] = kNaN;
    exr::write(p.string(), t);  // the writer stores what it is given
    const Loaded l = load(p.string());
    CHECK(l.info.counts.valid == 21);
    CHECK(l.info.counts.inf == 1);
    CHECK(l.info.counts.negative == 1);
    CHECK(l.info.counts.nan == 1);
    check_evaluates(*l.brdf);
    for (std::size_t k = 0; k < 3 * t.bins(); ++k) t.data()[k] = k % 2 ? -1.0f : kInf;
    exr::write(p.string(), t);
    CHECK_THAT(load_error(p), Catch::Contains("no valid value in the table"));
}
