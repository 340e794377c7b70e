#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/cornell.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = std::numbers::pi;

std::vector<double> decades() {  // 400, 410, ..., 700 nm, as the Cornell files
    std::vector<double> nm;
    for (int k = 0; k <= 30; ++k) nm.push_back(400.0 + 10.0 * k);
    return nm;
}

struct Record {
    double theta_i, phi_i, theta_o, phi_o;
    std::vector<double> spectrum;
};

std::string cornell_text(const std::vector<double>& nm, const std::vector<Record>& records) {
    std::ostringstream s;
    s.precision(17);
    s << "# synthetic Cornell file\n\n# num wls\n" << nm.size() << "\n\n# wls\n";
    for (std::size_t k = 0; k < nm.size(); ++k) s << nm[k] << (k % 19 == 18 ? "\n" : " ");
    s << "\n\n# theta i  phi i  theta s  phi_s  spectral sample values\n\n";
    for (const Record& r : records) {
        s << r.theta_i << " " << r.phi_i << " " << r.theta_o << " " << r.phi_o;
        for (double v : r.spectrum) s << " " << v;
        s << "\n";
    }
    return s.str();
}

fs::path write(const test::TempDir& dir, const std::string& name, const std::string& text) {
    const fs::path p = dir.path / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
}

Record flat(double theta_i, double phi_i, double theta_o, double phi_o, double level, std::size_t n = 31) {
    return {theta_i, phi_i, theta_o, phi_o, std::vector<double>(n, level)};
}

// The first line of a message naming the file and a line number, e.g. "f.brdf: line 12: ...".
std::string at_line(const fs::path& p, int line) { return p.string() + ": line " + std::to_string(line) + ":"; }

// A record line: four angles, then n copies of v.
std::string record_line(const std::string& angles, int n = 31, const std::string& v = "0.1") {
    std::string s = angles;
    for (int k = 0; k < n; ++k) s += " " + v;
    return s;
}

fs::path shared_cornell() { return fs::path(BRDFZ_SHARED_DIR) / "data" / "cornell"; }

}  // namespace

TEST_CASE("Spectral weights: a flat spectrum is exactly grey, at its level", "[cornell]") {
    const std::vector<double> nm = decades();
    const std::vector<Rgb> w = cornell::rgb_weights(nm);
    REQUIRE(w.size() == nm.size());
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (const Rgb& r : w) sum += r[c];
        CHECK(sum == Approx(1.0).margin(1e-14));
    }
    // Uneven sampling over the full table range: still grey.
    const std::vector<double> uneven{380, 395, 420, 433.5, 470, 500, 555, 600, 640, 700, 745, 780};
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (const Rgb& r : cornell::rgb_weights(uneven)) sum += r[c];
        CHECK(sum == Approx(1.0).margin(1e-14));
    }
}

TEST_CASE("Spectral weights agree with Mitsuba 3's spectrum_list_to_srgb under D65", "[cornell][qemu]") {
    // Reference: mitsuba 3.9.1, scalar_rgb, spectrum_list_to_srgb(400..700 step 10, s, bounded=False,
    // d65=True), an independent integration (1 nm CIE tables, its own normalisation: a flat spectrum
    // gives (0.9953, 0.9998, 0.9949) there, exactly 1 here), hence the 1.5% tolerance.
    const std::vector<double> nm = decades();
    const std::vector<Rgb> w = cornell::rgb_weights(nm);
    auto rgb_of = [&](auto&& s) {
        Rgb out{};
        for (std::size_t k = 0; k < nm.size(); ++k)
            for (int c = 0; c < 3; ++c) out[c] += w[k][c] * s(nm[k]);
        return out;
    };
    const Rgb ramp = rgb_of([](double l) { return (l - 400.0) / 300.0; });
    const Rgb bump = rgb_of([](double l) { return 0.2 + 0.6 * std::exp(-std::pow((l - 550.0) / 40.0, 2)); });
    const Rgb mitsuba_ramp{0.804148, 0.476456, 0.136042}, mitsuba_bump{0.264402, 0.656395, 0.164107};
    for (int c = 0; c < 3; ++c) {
        CHECK(ramp[c] == Approx(mitsuba_ramp[c]).epsilon(0.015));
        CHECK(bump[c] == Approx(mitsuba_bump[c]).epsilon(0.015));
    }
}

TEST_CASE("Spectral weights reject unusable wavelengths", "[cornell]") {
    CHECK_THROWS_AS(cornell::rgb_weights(std::vector<double>{550.0}), ValueError);
    CHECK_THROWS_AS(cornell::rgb_weights(std::vector<double>{500.0, 500.0}), ValueError);
    CHECK_THROWS_AS(cornell::rgb_weights(std::vector<double>{370.0, 500.0}), ValueError);
    CHECK_THROWS_AS(cornell::rgb_weights(std::vector<double>{500.0, 790.0}), ValueError);
    // 600..610 nm has no blue response worth the name.
    CHECK_THROWS_AS(cornell::rgb_weights(std::vector<double>{600.0, 605.0, 610.0}), ValueError);
}

TEST_CASE("Cornell reader: flat spectrum gives grey, directions land where the angles say", "[cornell][qemu]") {
    test::TempDir dir;
    const double t30 = kPi / 6, t45 = kPi / 4;
    const fs::path p = write(dir, "grey.brdf", cornell_text(decades(), {flat(t30, 0.0, t45, kPi / 2, 0.25),
                                                                         flat(0.0, 1.0, t30, kPi, 3.0)}));
    const cornell::ReadResult r = cornell::read(p.string());
    CHECK(r.records == 2);
    CHECK(r.wavelengths == decades());
    CHECK(r.counts.valid == 2);
    CHECK(r.counts.negative + r.counts.nan + r.counts.inf + r.counts.below_horizon + r.negative_spectral == 0);
    REQUIRE(r.set.samples.size() == 2);
    CHECK(r.set.channels == 3);
    CHECK(r.set.source == p.string());

    const Measurement& a = r.set.samples[0];
    for (int c = 0; c < 3; ++c) CHECK(a.f[c] == Approx(0.25).margin(1e-14));
    CHECK(a.wi.x == Approx(0.5));
    CHECK(a.wi.y == Approx(0.0).margin(1e-15));
    CHECK(a.wi.z == Approx(std::sqrt(3.0) / 2));
    CHECK(a.wo.x == Approx(0.0).margin(1e-15));
    CHECK(a.wo.y == Approx(std::sqrt(0.5)));
    CHECK(a.wo.z == Approx(std::sqrt(0.5)));

    const Measurement& b = r.set.samples[1];
    for (int c = 0; c < 3; ++c) CHECK(b.f[c] == Approx(3.0).margin(1e-13));
    CHECK(b.wi.z == Approx(1.0));
    CHECK(b.wo.x == Approx(-0.5));  // φo = π: the forward side of the +x incidence plane
    CHECK(b.wo.z == Approx(std::sqrt(3.0) / 2));
}

TEST_CASE("Cornell reader: a red spectrum is red, a blue one blue", "[cornell]") {
    test::TempDir dir;
    std::vector<double> red(31, 0.0), blue(31, 0.0);
    for (int k = 20; k < 31; ++k) red[k] = 1.0;  // 600..700 nm
    for (int k = 3; k < 9; ++k) blue[k] = 1.0;   // 430..480 nm
    const fs::path p =
        write(dir, "colours.brdf", cornell_text(decades(), {{0.3, 0, 0.3, kPi, red}, {0.3, 0, 0.3, kPi, blue}}));
    const cornell::ReadResult r = cornell::read(p.string());
    const Rgb& fr = r.set.samples.at(0).f;
    const Rgb& fb = r.set.samples.at(1).f;
    CHECK(fr[0] > 4 * fr[1]);
    CHECK(fr[0] > 4 * std::abs(fr[2]));
    CHECK(fb[2] > 4 * fb[0]);
    CHECK(fb[2] > 2 * fb[1]);
}

TEST_CASE("Cornell reader: NaN, Inf, negative and below-horizon records are counted", "[cornell]") {
    test::TempDir dir;
    const std::string body = cornell_text(decades(), {flat(0.2, 0, 0.2, kPi, 0.1)});
    // Records with one odd spectral value: "nan", "inf" and an overflowing literal parse as such; a
    // negative value is kept; a record at θo = 90° and one at θi = 100° are below the horizon.
    auto row = [](const std::string& angles, const std::string& v) {
        std::string s = angles;
        for (int k = 0; k < 31; ++k) s += " " + (k == 7 ? v : std::string("0.1"));
        return s + "\n";
    };
    std::string text = body;
    text += row("0.2 0 0.2 3.14159", "nan");
    text += row("0.2 0 0.2 3.14159", "inf");
    text += row("0.2 0 0.2 3.14159", "-1e999");
    text += row("0.2 0 0.2 3.14159", "-0.05");
    text += row("0.2 0 1.5707963267948966 3.14159", "0.1");
    text += row("1.7453292519943295 0 0.2 3.14159", "0.1");
    text += row("0.2 0 0.2 3.14159", "1e-400");  // underflows to 0: a valid value
    const fs::path p = write(dir, "counts.brdf", text);
    const cornell::ReadResult r = cornell::read(p.string());
    CHECK(r.records == 8);
    CHECK(r.counts.nan == 1);
    CHECK(r.counts.inf == 2);
    CHECK(r.counts.below_horizon == 2);
    CHECK(r.negative_spectral == 1);
    // A flat 0.1 with one sample at -0.05 stays positive in every channel.
    CHECK(r.counts.negative == 0);
    CHECK(r.counts.valid == 3);
    CHECK(r.set.samples.size() == 3);

    // A strongly negative spectrum gives negative RGB: kept and counted.
    std::string neg = body + row("0.2 0 0.2 3.14159", "-40");
    const cornell::ReadResult rn = cornell::read(write(dir, "neg.brdf", neg).string());
    CHECK(rn.counts.negative == 1);
    CHECK(rn.set.samples.size() == 2);
}

TEST_CASE("Cornell reader: malformed files name the file and line", "[cornell]") {
    test::TempDir dir;
    const std::string good = cornell_text(decades(), {flat(0.2, 0, 0.2, kPi, 0.1)});
    auto expect_format = [&](const std::string& name, const std::string& text, int line, const std::string& what) {
        const fs::path p = write(dir, name, text);
        INFO(name);
        try {
            cornell::read(p.string());
            FAIL("no exception");
        } catch (const FormatError& e) {
            const std::string msg = e.what();
            if (line > 0) CHECK_THAT(msg, Contains(at_line(p, line)));
            CHECK_THAT(msg, Contains(what));
        }
    };
    // The good file's lines: 1 comment, 2 blank, 3 comment, 4 count, 5 blank, 6 comment, 7-8
    // wavelengths, 9 blank, 10 comment, 11 blank, 12 the record.
    REQUIRE(cornell::read(write(dir, "good.brdf", good).string()).records == 1);
    auto replace_line = [&](int line, const std::string& with) {
        std::istringstream in(good);
        std::string out, l;
        for (int k = 1; std::getline(in, l); ++k) out += (k == line ? with : l) + "\n";
        return out;
    };
    expect_format("empty.brdf", "", 0, "no wavelength count");
    expect_format("comments.brdf", "# nothing\n#\n", 0, "no wavelength count");
    expect_format("count-real.brdf", replace_line(4, "31.5"), 4, "number of wavelengths");
    expect_format("count-huge.brdf", replace_line(4, "99999999999999999999999"), 4, "number of wavelengths");
    expect_format("count-one.brdf", replace_line(4, "1"), 4, "number of wavelengths");
    expect_format("count-two.brdf", replace_line(4, "31 32"), 4, "more than one number");
    expect_format("wl-order.brdf", replace_line(7, "400 410 420 430 440 450 460 470 480 490 500 510 520 530 540 550 560 570 570"),
                  7, "increase strictly");
    expect_format("wl-text.brdf", replace_line(7, "400 410 blue"), 7, "expected a wavelength");
    expect_format("wl-many.brdf", replace_line(8, "590 600 610 620 630 640 650 660 670 680 690 700 710"), 8,
                  "more wavelengths");
    expect_format("wl-short.brdf", "31\n400 410 420\n", 0, "ends after 3 of the 31 wavelengths");
    expect_format("short.brdf", replace_line(12, "0.2 0 0.2 3.14159 0.1 0.1"), 12, "needs 35 numbers");
    expect_format("long.brdf", replace_line(12, record_line("0.2 0 0.2 3.14159", 32)), 12, "more than the 35 numbers");
    expect_format("text.brdf", replace_line(12, "0.2 0 0.2 pi"), 12, "expected a number, found 'pi'");
    expect_format("hex.brdf", replace_line(12, "0x1p-3 0 0.2 3"), 12, "expected a number");
    expect_format("angle-nan.brdf", good + record_line("nan 0 0.2 3") + "\n", 13, "angle 1 is not finite");
    expect_format("angle-range.brdf", good + record_line("0.2 0 4 0") + "\n", 13, "outside [0, pi]");
    expect_format("negative-theta.brdf", good + record_line("-0.1 0 0.2 0") + "\n", 13, "outside [0, pi]");
    expect_format("no-records.brdf", replace_line(12, "# gone"), 0, "no measurement records");
    expect_format("all-below.brdf", replace_line(12, record_line("1.6 0 0.2 0")), 0, "no usable record");
    expect_format("binary.brdf", std::string("31\n\x01\x02\xff\x00garbage", 14), 2, "expected a wavelength in nm, found '????garbage'");
}

TEST_CASE("Cornell reader: unsupported wavelengths and unreadable files", "[cornell]") {
    test::TempDir dir;
    std::vector<double> uv = decades();
    uv[0] = 350;
    const fs::path p = write(dir, "uv.brdf", cornell_text(uv, {flat(0.2, 0, 0.2, kPi, 0.1)}));
    CHECK_THROWS_WITH(cornell::read(p.string()), Contains(at_line(p, 7)) && Contains("outside the 380..780 nm"));
    CHECK_THROWS_AS(cornell::read(p.string()), UnsupportedError);
    const fs::path narrow = write(dir, "narrow.brdf", cornell_text({600, 605, 610}, {flat(0.2, 0, 0.2, kPi, 0.1, 3)}));
    CHECK_THROWS_AS(cornell::read(narrow.string()), UnsupportedError);
    CHECK_THROWS_AS(cornell::read((dir.path / "missing.brdf").string()), IoError);
    CHECK_THROWS_AS(cornell::read(dir.path.string()), IoError);
}

TEST_CASE("Cornell reader: arbitrary bytes never crash, only throw brdfz errors", "[cornell][fuzz]") {
    test::TempDir dir;
    const std::string good = cornell_text(decades(), {flat(0.2, 0, 0.2, kPi, 0.1), flat(0.4, 0, 0.5, 3.0, 0.2)});
    std::mt19937 rng(7);
    const char alphabet[] = "0123456789.-+eE nainf#\n\t\r\x00\xff";
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
        const fs::path p = write(dir, "fuzz.brdf", text);
        try {
            const cornell::ReadResult r = cornell::read(p.string());
            for (const Measurement& m : r.set.samples) {
                CHECK(m.wi.z > 0.0);
                CHECK(m.wo.z > 0.0);
                CHECK((std::isfinite(m.f[0]) && std::isfinite(m.f[1]) && std::isfinite(m.f[2])));
            }
        } catch (const Error&) {
        }
    }
}

TEST_CASE("Cornell shared data: 1,439 records per file, peaks in the plane of incidence", "[cornell][data][qemu]") {
    const fs::path dir = shared_cornell();
    if (!fs::is_directory(dir)) {
        WARN("skipped: ../shared/data/cornell missing");
        return;
    }
    for (const char* name : {"cayman", "garnet_red", "mystique"}) {
        INFO(name);
        const cornell::ReadResult r = cornell::read((dir / (std::string(name) + ".brdf")).string());
        CHECK(r.records == 1439);
        CHECK(r.wavelengths == decades());
        CHECK(r.set.samples.size() == 1439);
        CHECK(r.counts.nan + r.counts.inf + r.counts.below_horizon + r.negative_spectral == 0);
        CHECK(r.counts.valid + r.counts.negative == 1439);

        // The largest value of each θi slice: on the forward side of the incidence plane, and for the
        // high-gloss paints within 5° of the mirror direction.
        std::vector<const Measurement*> peak(9, nullptr);
        double lo = INFINITY, hi = -INFINITY;
        for (const Measurement& m : r.set.samples) {
            const double mean = (m.f[0] + m.f[1] + m.f[2]) / 3;
            lo = std::min(lo, mean);
            hi = std::max(hi, mean);
            const int slice = static_cast<int>(std::lround(elevation(m.wi) * 180 / kPi / 10));
            REQUIRE(slice >= 1);
            REQUIRE(slice <= 8);
            if (!peak[slice] || mean > (peak[slice]->f[0] + peak[slice]->f[1] + peak[slice]->f[2]) / 3) peak[slice] = &m;
        }
        CHECK(hi > 10.0);   // glossy peaks, 1/sr
        CHECK(lo > -0.1);   // out-of-gamut negatives are small
        for (int s = 1; s <= 8; ++s) {
            const Measurement& m = *peak[s];
            const double azimuth_gap = std::atan2(m.wi.x * m.wo.y - m.wi.y * m.wo.x, m.wi.x * m.wo.x + m.wi.y * m.wo.y);
            CHECK(std::abs(std::abs(azimuth_gap) - kPi) < 1e-3);
            if (std::string(name) != "garnet_red") {
                const Vec3 mirror{-m.wi.x, -m.wi.y, m.wi.z};
                CHECK(std::acos(std::min(1.0, dot(mirror, m.wo))) < 5 * kPi / 180);
            }
        }
    }
    // Colours: garnet red's diffuse samples are red, cayman's blue-green.
    auto mean_rgb = [&](const char* name) {
        const cornell::ReadResult r = cornell::read((dir / (std::string(name) + ".brdf")).string());
        Rgb sum{};
        for (const Measurement& m : r.set.samples)
            if (dot(Vec3{-m.wi.x, -m.wi.y, m.wi.z}, m.wo) < std::cos(0.5))  // away from the mirror peak
                for (int c = 0; c < 3; ++c) sum[c] += m.f[c];
        return sum;
    };
    const Rgb garnet = mean_rgb("garnet_red"), cayman = mean_rgb("cayman");
    CHECK(garnet[0] > 3 * garnet[1]);
    CHECK(garnet[0] > 3 * garnet[2]);
    CHECK(cayman[2] > 3 * cayman[0]);
}

TEST_CASE("load_measurements: Cornell source info", "[cornell][io]") {
    test::TempDir dir;
    const fs::path p = write(dir, "two.brdf", cornell_text(decades(), {flat(0.2, 0, 0.2, kPi, 0.5), flat(0.3, 0, 0.2, kPi, 2.0)}));
    CHECK(holds_measurements(p.string()));
    const LoadedMeasurements m = load_measurements(p.string());
    CHECK(m.info.format == "cornell");
    CHECK(m.info.dims == std::vector<std::size_t>{2, 31});
    CHECK(m.info.counts.valid == 2);
    CHECK(m.info.min_value == Approx(0.5));
    CHECK(m.info.max_value == Approx(2.0));
    CHECK(m.set.samples.size() == 2);
    CHECK_THROWS_AS(load(p.string()), UnsupportedError);
}

TEST_CASE("Metrics at measured points: a BRDF against its own values is exact", "[cornell][metrics]") {
    const CoatedDiffuse brdf;
    MeasurementSet set;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 2000; ++k) {
        const Vec3 wi = spherical_direction(0.5 * kPi * u(rng), 2 * kPi * u(rng));
        const Vec3 wo = spherical_direction(0.5 * kPi * u(rng), 2 * kPi * u(rng));
        set.samples.push_back({wi, wo, brdf.eval(wi, wo)});
    }
    std::size_t inside = 0;
    const double min_cos = std::cos(80 * kPi / 180);
    for (const Measurement& m : set.samples) inside += m.wi.z > min_cos && m.wo.z > min_cos;

    const Metrics same = compare(set, brdf);
    CHECK(same.samples == inside);
    CHECK(same.cos_rmse.mean == 0.0);
    CHECK(same.cos_rmse_rel.mean == 0.0);
    CHECK(same.log_rmse.mean == 0.0);
    CHECK(same.cbrt_rmse.mean == 0.0);

    // 10% too bright everywhere: the relative cosine-weighted error is exactly 0.1.
    MeasurementSet dimmer = set;
    for (Measurement& m : dimmer.samples)
        for (double& v : m.f) v /= 1.1;
    const Metrics off = compare(dimmer, brdf);
    CHECK(off.cos_rmse_rel.r == Approx(0.1));
    CHECK(off.cos_rmse_rel.b == Approx(0.1));
    CHECK(off.cos_rmse.mean > 0.0);

    MetricOptions narrow;
    narrow.max_theta_deg = 0.01;
    CHECK_THROWS_AS(compare(set, brdf, narrow), ValueError);
}
