#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/alta.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = std::numbers::pi;

fs::path write(const test::TempDir& dir, const std::string& name, const std::string& text) {
    const fs::path p = dir.path / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
}

std::string header(const std::string& param, int dim, const std::string& extra = "", int outputs = 1) {
    return "#SAMPLE \"synthetic\"\n#DIM " + std::to_string(dim) + " " + std::to_string(outputs) + "\n" + extra +
           "#PARAM_IN " + param + "\n";
}

std::string at_line(const fs::path& p, int line) { return p.string() + ": line " + std::to_string(line) + ":"; }

double angle_between(const Vec3& a, const Vec3& b) { return std::acos(std::clamp(dot(a, b), -1.0, 1.0)); }

// φ difference wrapped into (-π, π].
double wrap(double phi) { return std::remainder(phi, 2 * kPi); }

}  // namespace

TEST_CASE("ALTA projected-Δφ rows land at the right wi and wo", "[alta][qemu]") {
    test::TempDir dir;
    const fs::path p = write(dir, "proj.dat",
                             header("ISOTROPIC_TL_TV_PROJ_DPHI", 3, "#VS 0\n") +
                                 "0.5 0.3 -0.4 0.25\n"  // θv = 0.5 at Δφ = atan2(-0.4, 0.3)
                                 "1.0 0 0 1.5\n"        // view along the normal
                                 "0.2 0.2 0 7\n");      // retro-reflection: wo = wi
    const alta::ReadResult r = alta::read(p.string());
    CHECK(r.param_in == "ISOTROPIC_TL_TV_PROJ_DPHI");
    CHECK(r.rows == 3);
    CHECK(r.counts.valid == 3);
    REQUIRE(r.set.samples.size() == 3);
    CHECK(r.set.channels == 1);

    const Measurement& a = r.set.samples[0];
    CHECK(a.f == Rgb{0.25, 0.25, 0.25});
    CHECK(a.wi.x == Approx(std::sin(0.5)));
    CHECK(a.wi.y == 0.0);
    CHECK(a.wi.z == Approx(std::cos(0.5)));
    CHECK(a.wo.x == Approx(std::sin(0.5) * 0.6));
    CHECK(a.wo.y == Approx(-std::sin(0.5) * 0.8));
    CHECK(a.wo.z == Approx(std::cos(0.5)));

    const Measurement& b = r.set.samples[1];
    CHECK(b.wo.x == 0.0);
    CHECK(b.wo.y == 0.0);
    CHECK(b.wo.z == 1.0);

    const Measurement& c = r.set.samples[2];
    CHECK(angle_between(c.wi, c.wo) < 1e-12);
}

TEST_CASE("ALTA Rusinkiewicz rows: d is the view, as ALTA packs [V, L]", "[alta]") {
    test::TempDir dir;
    SECTION("RUSIN_TH_TD_PD") {
        const fs::path p = write(dir, "rusin3.dat", header("RUSIN_TH_TD_PD", 3) + "0.3 0.4 1.0 2\n");
        const Measurement m = alta::read(p.string()).set.samples.at(0);
        const HalfDiff v = to_half_diff(m.wo, m.wi);  // d measured from the view
        CHECK(v.theta_h == Approx(0.3));
        CHECK(v.phi_h == Approx(0.0).margin(1e-12));
        CHECK(v.theta_d == Approx(0.4));
        CHECK(v.phi_d == Approx(1.0));
        const HalfDiff l = to_half_diff(m.wi, m.wo);  // our convention: the same pair at φd + π
        CHECK(wrap(l.phi_d - (1.0 + kPi)) == Approx(0.0).margin(1e-12));
        CHECK(std::hypot(m.wi.x, m.wi.y, m.wi.z) == Approx(1.0));
    }
    SECTION("RUSIN_TH_TD sits at φd = π/2") {
        const fs::path p = write(dir, "rusin2.dat", header("RUSIN_TH_TD", 2, "#PARAM_OUT INV_STERADIAN\n") + "0.2 0.6 3\n");
        const Measurement m = alta::read(p.string()).set.samples.at(0);
        const HalfDiff v = to_half_diff(m.wo, m.wi);
        CHECK(v.theta_h == Approx(0.2));
        CHECK(v.theta_d == Approx(0.6));
        CHECK(v.phi_d == Approx(kPi / 2));
    }
    SECTION("RUSIN_TH_PH_TD_PD keeps φh") {
        const fs::path p = write(dir, "rusin4.dat", header("RUSIN_TH_PH_TD_PD", 4) + "0.5 0.7 0.3 -2.0 3\n");
        const Measurement m = alta::read(p.string()).set.samples.at(0);
        const HalfDiff v = to_half_diff(m.wo, m.wi);
        CHECK(v.theta_h == Approx(0.5));
        CHECK(v.phi_h == Approx(0.7));
        CHECK(v.theta_d == Approx(0.3));
        CHECK(v.phi_d == Approx(-2.0));
    }
}

TEST_CASE("ALTA header variants: #VS columns, comments, END HEADER", "[alta]") {
    test::TempDir dir;
    const std::string rows = "0.2 0.1 0 1.0";
    SECTION("VS 1: one extra column") {
        const fs::path p = write(dir, "vs1.dat", header("ISOTROPIC_TL_TV_PROJ_DPHI", 3, "#VS 1\n") + rows + " 0.1\n");
        CHECK(alta::read(p.string()).set.samples.at(0).f[0] == 1.0);
    }
    SECTION("VS 2: min and max columns") {
        const fs::path p = write(dir, "vs2.dat", header("ISOTROPIC_TL_TV_PROJ_DPHI", 3, "#VS 2\n") + rows + " 0.9 1.1\n");
        CHECK(alta::read(p.string()).set.samples.at(0).f[0] == 1.0);
    }
    SECTION("comments, blank lines, CRLF and an explicit end of header") {
        const fs::path p = write(dir, "crlf.dat",
                                 "# a comment\r\n#DIM 3 1\r\n\r\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\r\n#ALTA END HEADER\r\n"
                                 "#NOT_A_KEY after the header is a comment\r\n" +
                                     rows + "\r\n# trailing comment\r\n");
        const alta::ReadResult r = alta::read(p.string());
        CHECK(r.rows == 1);
        CHECK(r.set.samples.at(0).f[0] == 1.0);
    }
}

TEST_CASE("ALTA reader: NaN, Inf, negative and below-horizon rows are counted", "[alta][qemu]") {
    test::TempDir dir;
    const fs::path p = write(dir, "counts.dat",
                             header("ISOTROPIC_TL_TV_PROJ_DPHI", 3) +
                                 "0.2 0.1 0 1.0\n"
                                 "0.2 0.1 0 nan\n"
                                 "0.2 0.1 0 -inf\n"
                                 "0.2 0.1 0 1e400\n"
                                 "0.2 0.1 0 -0.01\n"
                                 "0.2 -1.5707963267948966 0 0.5\n"  // θv = 90°: on the horizon
                                 "0.2 -2.0 0.5 0.5\n"               // θv > 90°
                                 "1.5707963267948966 0.1 0 0.5\n"); // θl = 90°
    const alta::ReadResult r = alta::read(p.string());
    CHECK(r.rows == 8);
    CHECK(r.counts.valid == 1);
    CHECK(r.counts.negative == 1);
    CHECK(r.counts.nan == 1);
    CHECK(r.counts.inf == 2);
    CHECK(r.counts.below_horizon == 3);
    REQUIRE(r.set.samples.size() == 2);
    CHECK(r.set.samples[1].f == Rgb{-0.01, -0.01, -0.01});  // kept as measured
}

TEST_CASE("ALTA reader: malformed and unsupported files", "[alta]") {
    test::TempDir dir;
    const std::string proj = "ISOTROPIC_TL_TV_PROJ_DPHI";
    auto check_error = [&](const std::string& name, const std::string& text, int line, const std::string& what,
                           bool unsupported = false) {
        const fs::path p = write(dir, name, text);
        INFO(name);
        try {
            alta::read(p.string());
            FAIL("no exception");
        } catch (const UnsupportedError& e) {
            CHECK(unsupported);
            CHECK_THAT(std::string(e.what()), Contains(p.string() + ": ") && Contains(what));
        } catch (const FormatError& e) {
            CHECK_FALSE(unsupported);
            const std::string msg = e.what();
            if (line > 0) CHECK_THAT(msg, Contains(at_line(p, line)));
            CHECK_THAT(msg, Contains(what));
        }
    };
    // Lines of header(proj, 3): 1 #SAMPLE, 2 #DIM, 3 #PARAM_IN; data from line 4.
    check_error("empty.dat", "", 0, "no #DIM");
    check_error("no-dim.dat", "#PARAM_IN " + proj + "\n0.2 0.1 0 1\n", 0, "no #DIM");
    check_error("no-param.dat", "#DIM 3 1\n0.2 0.1 0 1\n", 0, "no #PARAM_IN");
    check_error("dim-twice.dat", header(proj, 3) + "#DIM 3 1\n0.2 0.1 0 1\n", 4, "repeated #DIM");
    check_error("dim-bad.dat", "#DIM 3\n", 1, "#DIM needs two integers");
    check_error("dim-huge.dat", "#DIM 3 99999999999999999999999\n", 1, "#DIM needs two integers");
    check_error("dim-mismatch.dat", header(proj, 2) + "0.2 0.1 1\n", 0, "has 3 coordinates");
    check_error("vs-bad.dat", header(proj, 3, "#VS 3\n") + "0.2 0.1 0 1\n", 3, "#VS needs one of 0, 1, 2");
    check_error("param-empty.dat", "#DIM 3 1\n#PARAM_IN\n", 2, "#PARAM_IN needs a value");
    check_error("short.dat", header(proj, 3) + "0.2 0.1 0 1\n0.2 0.1\n", 5, "a row needs 4 numbers");
    check_error("long.dat", header(proj, 3) + "0.2 0.1 0 1 5\n", 4, "more than the 4 numbers");
    check_error("vs-missing.dat", header(proj, 3, "#VS 2\n") + "0.2 0.1 0 1 0.9\n", 5, "a row needs 6 numbers");
    check_error("text.dat", header(proj, 3) + "0.2 0.1 zero 1\n", 4, "expected a number, found 'zero'");
    check_error("coord-nan.dat", header(proj, 3) + "nan 0.1 0 1\n", 4, "coordinate 1 is not finite");
    check_error("coord-inf.dat", header(proj, 3) + "0.2 inf 0 1\n", 4, "coordinate 2 is not finite");
    check_error("theta-l.dat", header(proj, 3) + "4 0.1 0 1\n", 4, "theta_l");
    check_error("theta-v.dat", header(proj, 3) + "0.2 3 2 1\n", 4, "theta_v");
    check_error("theta-d.dat", header("RUSIN_TH_TD_PD", 3) + "0.2 -0.1 0 1\n", 4, "theta_d");
    check_error("no-rows.dat", header(proj, 3), 0, "no data rows");
    check_error("all-below.dat", header(proj, 3) + "0.2 1.6 0 1\n", 0, "no usable row");
    check_error("binary-garbage.dat", header(proj, 3) + std::string("\x01\x02\xff\x00\x10", 5) + "\n", 4,
                "expected a number, found '" + std::string(5, '?') + "'");
    check_error("param-unknown.dat", header("STARK_2D", 2) + "0.1 0.2 1\n", 0, "STARK_2D", true);
    check_error("two.dat", "#DIM 3 2\n#PARAM_IN " + proj + "\n0.2 0.1 0 1 1\n", 0, "one (monochrome) or three", true);
    check_error("rgb-one.dat", header(proj, 3, "#PARAM_OUT RGB_COLOR\n") + "0.2 0.1 0 1\n", 0, "three (R, G, B)", true);
    check_error("xyz.dat", "#DIM 3 3\n#PARAM_OUT XYZ_COLOR\n#PARAM_IN " + proj + "\n0.2 0.1 0 1 1 1\n", 0,
                "XYZ_COLOR", true);
    check_error("rgb-short.dat", "#DIM 3 3\n#PARAM_IN " + proj + "\n0.2 0.1 0 1 1\n", 3, "the 3 values");
    check_error("cartesian-zero.dat", header("CARTESIAN", 6) + "0 0 1 0 0 0 1\n", 4, "light vector L");
    check_error("spherical-theta.dat", header("SPHERICAL_TL_PL_TV_PV", 4) + "0.2 0 -1 0 1\n", 4, "theta_v");
    check_error("binary.dat",
                header(proj, 3, "#FORMAT binary\n#VERSION 0\n#BEGIN_STREAM\n") + std::string("\x00\x01\x02", 3), 0,
                "only text files", true);
    CHECK_THROWS_AS(alta::read((dir.path / "missing.dat").string()), IoError);
}

TEST_CASE("ALTA #PARAM_OUT INV_STERADIAN_COSINE_FACTOR: values are f_r·cosθi", "[alta]") {
    test::TempDir dir;
    // θl = 1.0: f = value / cos(1.0); the view's elevation does not enter.
    const fs::path p = write(dir, "cos.dat",
                             header("ISOTROPIC_TL_TV_PROJ_DPHI", 3, "#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n") +
                                 "1.0 0.3 -0.4 0.25\n0.0 1.2 0 0.5\n");
    const alta::ReadResult r = alta::read(p.string());
    CHECK(r.param_out == "INV_STERADIAN_COSINE_FACTOR");
    REQUIRE(r.set.samples.size() == 2);
    CHECK(r.set.samples[0].f[0] == Approx(0.25 / std::cos(1.0)));
    CHECK(r.set.samples[0].f[2] == r.set.samples[0].f[0]);
    CHECK(r.set.samples[1].f[0] == Approx(0.5));  // light along the normal
    CHECK(r.set.channels == 1);
}

TEST_CASE("ALTA three outputs: RGB_COLOR and #DIM 3 3 / 4 3", "[alta]") {
    test::TempDir dir;
    SECTION("RGB_COLOR, projected Δφ, with #VS after the three values") {
        const fs::path p = write(dir, "rgb.dat",
                                 "#DIM 3 3\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT RGB_COLOR\n#VS 2\n"
                                 "0.5 0.3 -0.4 0.1 0.2 0.3 0.05 0.15\n");
        const alta::ReadResult r = alta::read(p.string());
        CHECK(r.param_out == "RGB_COLOR");
        CHECK(r.set.channels == 3);
        CHECK(r.set.samples.at(0).f == Rgb{0.1, 0.2, 0.3});
        CHECK(r.counts.valid == 1);
    }
    SECTION("#DIM 4 3 in 1/sr, RUSIN_TH_PH_TD_PD") {
        const fs::path p = write(dir, "rgb4.dat", header("RUSIN_TH_PH_TD_PD", 4, "", 3) + "0.5 0.7 0.3 -2.0 1 2 3\n");
        const alta::ReadResult r = alta::read(p.string());
        CHECK(r.set.channels == 3);
        const Measurement& m = r.set.samples.at(0);
        CHECK(m.f == Rgb{1, 2, 3});
        const HalfDiff v = to_half_diff(m.wo, m.wi);
        CHECK(v.theta_h == Approx(0.5));
        CHECK(v.phi_d == Approx(-2.0));
    }
    SECTION("three cosine-weighted values, and a negative channel counted") {
        const fs::path p = write(dir, "rgbcos.dat",
                                 "#DIM 3 3\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n"
                                 "0.6 0.3 0 0.3 0.6 -0.01\n0.6 0.3 0 0.3 nan 1\n");
        const alta::ReadResult r = alta::read(p.string());
        REQUIRE(r.set.samples.size() == 1);
        const double c = std::cos(0.6);
        CHECK(r.set.samples[0].f[0] == Approx(0.3 / c));
        CHECK(r.set.samples[0].f[1] == Approx(0.6 / c));
        CHECK(r.set.samples[0].f[2] == Approx(-0.01 / c));
        CHECK(r.counts.negative == 1);
        CHECK(r.counts.nan == 1);
    }
}

TEST_CASE("ALTA CARTESIAN and SPHERICAL_TL_PL_TV_PV rows", "[alta]") {
    test::TempDir dir;
    SECTION("CARTESIAN packs [V, L]; vectors are normalised") {
        const fs::path p = write(dir, "cart.dat", header("CARTESIAN", 6) + "0 0 2 0.6 0 0.8 0.5\n");
        const Measurement m = alta::read(p.string()).set.samples.at(0);
        CHECK(m.wo.z == Approx(1.0));
        CHECK(m.wi.x == Approx(0.6));
        CHECK(m.wi.z == Approx(0.8));
        CHECK(m.f[0] == 0.5);
    }
    SECTION("SPHERICAL_TL_PL_TV_PV: light then view, each (θ, φ)") {
        const fs::path p = write(dir, "sph.dat", header("SPHERICAL_TL_PL_TV_PV", 4) + "0.4 1.0 0.9 -2.0 0.5\n");
        const Measurement m = alta::read(p.string()).set.samples.at(0);
        CHECK(elevation(m.wi) == Approx(0.4));
        CHECK(std::atan2(m.wi.y, m.wi.x) == Approx(1.0));
        CHECK(elevation(m.wo) == Approx(0.9));
        CHECK(std::atan2(m.wo.y, m.wo.x) == Approx(-2.0));
    }
    SECTION("a non-reciprocal RGB BRDF written in both forms, cosine-weighted, reads back as itself") {
        // f depends on which direction is the light: L and V must not be exchanged.
        const CoatedDiffuse lobe(CoatedDiffuseParams{{0.2, 0.4, 0.6}, 0.3, 1.5});
        const auto f = [&](const Vec3& wi, const Vec3& wo) {
            Rgb v = lobe.eval(wi, wo);
            for (double& c : v) c *= 1.0 + 0.5 * (wi.z - wo.z);
            return v;
        };
        std::string sph = "#DIM 4 3\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n";
        std::string cart = "#DIM 6 3\n#PARAM_IN CARTESIAN\n#PARAM_OUT RGB_COLOR\n";
        std::vector<std::pair<Vec3, Vec3>> pairs;
        std::mt19937_64 rng(9);
        std::uniform_real_distribution<double> u(0, 1);
        for (int k = 0; k < 200; ++k) {
            const double tl = 1.4 * u(rng), pl = 6.2 * u(rng) - 3.1, tv = 1.4 * u(rng), pv = 6.2 * u(rng) - 3.1;
            const Vec3 wi = spherical_direction(tl, pl), wo = spherical_direction(tv, pv);
            pairs.emplace_back(wi, wo);
            const Rgb v = f(wi, wo);
            char line[512];
            std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", tl, pl, tv, pv,
                          v[0] * wi.z, v[1] * wi.z, v[2] * wi.z);
            sph += line;
            std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", wo.x, wo.y,
                          wo.z, wi.x, wi.y, wi.z, v[0], v[1], v[2]);
            cart += line;
        }
        for (const auto& [name, text] : {std::pair{"sph3.dat", sph}, std::pair{"cart3.dat", cart}}) {
            INFO(name);
            const alta::ReadResult r = alta::read(write(dir, name, text).string());
            REQUIRE(r.set.samples.size() == pairs.size());
            CHECK(r.set.channels == 3);
            for (std::size_t k = 0; k < pairs.size(); ++k) {
                const Rgb want = f(pairs[k].first, pairs[k].second);
                for (int c = 0; c < 3; ++c) REQUIRE(r.set.samples[k].f[c] == Approx(want[c]).epsilon(1e-12));
                REQUIRE(length(r.set.samples[k].wi - pairs[k].first) < 1e-12);
                REQUIRE(length(r.set.samples[k].wo - pairs[k].second) < 1e-12);
            }
        }
    }
}

TEST_CASE("ALTA reader: arbitrary bytes never crash, only throw brdfz errors", "[alta][fuzz]") {
    test::TempDir dir;
    const std::string good = header("ISOTROPIC_TL_TV_PROJ_DPHI", 3, "#VS 0\n") +
                             "0.2 0.1 0 1.0\n0.5 -0.3 0.2 0.5\n#c\n1.0 0 0 2\n";
    std::mt19937 rng(11);
    const char alphabet[] = "0123456789.-+eE nainf#DIMVS\n\t\r\x00\xff";
    for (int trial = 0; trial < 400; ++trial) {
        std::string text = good;
        const int edits = 1 + static_cast<int>(rng() % 8);
        for (int e = 0; e < edits; ++e) {
            const std::size_t at = rng() % (text.size() + 1);
            switch (rng() % 3) {
                case 0: text.insert(at, 1, alphabet[rng() % (sizeof alphabet - 1)]); break;
                case 1: if (at < text.size()) text.erase(at, 1 + rng() % 20); break;
                default: if (at < text.size()) text[at] = static_cast<char>(rng() % 256); break;
            }
        }
        const fs::path p = write(dir, "fuzz.dat", text);
        try {
            const alta::ReadResult r = alta::read(p.string());
            for (const Measurement& m : r.set.samples) {
                CHECK(m.wi.z > 0.0);
                CHECK(m.wo.z > 0.0);
                CHECK(std::isfinite(m.f[0]));
            }
        } catch (const Error&) {
        }
    }
}

TEST_CASE("ALTA shared data: the CEA gray tape is retro-reflective", "[alta][data][qemu]") {
    const fs::path p = fs::path(BRDFZ_SHARED_DIR) / "data" / "alta" / "retro-gray-tape.dat";
    if (!fs::exists(p)) {
        WARN("skipped: ../shared/data/alta missing");
        return;
    }
    const alta::ReadResult r = alta::read(p.string());
    CHECK(r.param_in == "ISOTROPIC_TL_TV_PROJ_DPHI");
    CHECK(r.rows == 7405);
    // Rows measured at exactly θv = 90° are on the horizon; nothing else is dropped.
    CHECK(r.counts.below_horizon == 86);
    CHECK(r.counts.nan + r.counts.inf + r.counts.negative == 0);
    CHECK(r.set.samples.size() == 7405 - 86);

    // Per incidence: at 15° and 30° the brightest sample looks back along the light; at 60° the
    // retro-reflection is still several times the median, beside a specular lobe of similar height.
    for (double deg : {15.0, 30.0, 60.0}) {
        INFO(deg);
        std::vector<double> values;
        const Measurement* peak = nullptr;
        const Measurement* retro = nullptr;
        for (const Measurement& m : r.set.samples) {
            if (std::abs(elevation(m.wi) - deg * kPi / 180) > 1e-6) continue;
            values.push_back(m.f[0]);
            if (!peak || m.f[0] > peak->f[0]) peak = &m;
            if (!retro || angle_between(m.wi, m.wo) < angle_between(retro->wi, retro->wo)) retro = &m;
        }
        REQUIRE(values.size() > 1000);
        std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
        const double median = values[values.size() / 2];
        CHECK(angle_between(retro->wi, retro->wo) < 1e-6);  // a sample sits exactly at wo = wi
        CHECK(retro->f[0] > 3 * median);
        if (deg < 45) CHECK(angle_between(peak->wi, peak->wo) < 2 * kPi / 180);
    }
}

TEST_CASE("load_measurements: ALTA source info, metrics of a BRDF at its own values", "[alta][io][metrics]") {
    test::TempDir dir;
    const CoatedDiffuse brdf(CoatedDiffuseParams{{0.4, 0.4, 0.4}, 0.2, 1.5});
    // A monochrome BRDF (grey base, colourless coat) tabulated at ALTA's projected coordinates.
    std::string text = header("ISOTROPIC_TL_TV_PROJ_DPHI", 3);
    std::size_t rows = 0;
    for (double tl : {0.1, 0.5, 0.9, 1.3})
        for (double x = -1.5; x <= 1.5; x += 0.25)
            for (double y = -1.5; y <= 1.5; y += 0.25) {
                const double tv = std::hypot(x, y);
                if (tv >= kPi / 2) continue;
                const Vec3 wi{std::sin(tl), 0, std::cos(tl)};
                const double s = tv > 0 ? std::sin(tv) / tv : 0;
                const Vec3 wo{s * x, s * y, std::cos(tv)};
                char line[128];
                std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g\n", tl, x, y, brdf.eval(wi, wo)[0]);
                text += line;
                ++rows;
            }
    const fs::path p = write(dir, "self.dat", text);
    CHECK(holds_measurements(p.string()));
    const LoadedMeasurements m = load_measurements(p.string());
    CHECK(m.info.format == "alta");
    CHECK(m.info.dims == std::vector<std::size_t>{rows, 1});
    CHECK(m.info.counts.valid == rows);
    CHECK(m.info.min_value > 0.0);
    CHECK_THROWS_AS(load(p.string()), UnsupportedError);

    const Metrics self = compare(m.set, brdf);
    CHECK(self.samples > 0);
    CHECK(self.cos_rmse.mean < 1e-15);
    CHECK(self.log_rmse.mean < 1e-15);
    CHECK(self.cbrt_rmse.mean < 1e-12);
}
