#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/tabulate.h"
#include "detail/atomic_file.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

void write_raw(const fs::path& p, const std::vector<std::int32_t>& header, const std::vector<double>& payload,
               std::size_t extra = 0) {
    std::ofstream f(p, std::ios::binary);
    f.write(reinterpret_cast<const char*>(header.data()), header.size() * 4);
    f.write(reinterpret_cast<const char*>(payload.data()), payload.size() * 8);
    for (std::size_t k = 0; k < extra; ++k) f.put('\0');
}

std::vector<double> payload(int a, int b, int c, double v) { return std::vector<double>(3ull * a * b * c, v); }

std::vector<double> read_doubles(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    f.seekg(12);
    std::vector<double> v((fs::file_size(p) - 12) / 8);
    f.read(reinterpret_cast<char*>(v.data()), v.size() * 8);
    return v;
}

}  // namespace

TEST_CASE("MERL write then read is bit-identical, invalid bins included", "[merl][io][qemu]") {
    const test::TempDir dir;
    for (const GridSpec g : {GridSpec{16, 16, 32}, GridSpec{}}) {
        TabulateOptions o;
        o.grid = g;
        Tabulated t = tabulate(CoatedDiffuse(), o);
        t.table.invalidate(5);  // an unmeasured bin above the horizon too
        const fs::path p = dir.path / (g.str() + ".binary");
        merl::write(p.string(), t.table);
        CHECK(fs::file_size(p) == 12 + 24 * g.bins());
        const merl::ReadResult r = merl::read(p.string());
        CHECK(r.table == t.table);
        CHECK(r.counts.valid == t.counts.valid - 1);
        CHECK(r.counts.negative == g.bins() - r.counts.valid);  // unmeasured bins are written as -1
        // And a second write of what was read is byte-identical to the first.
        const fs::path q = dir.path / "again.binary";
        merl::write(q.string(), r.table);
        CHECK(read_doubles(p) == read_doubles(q));
    }
}

TEST_CASE("MERL layout: index φd + nφd·(θd + nθd·θh), channel planes, MERL scales", "[merl][io]") {
    const test::TempDir dir;
    const GridSpec g{4, 5, 6};
    Table t(g);
    for (std::size_t b = 0; b < t.bins(); ++b) t.set(b, {1.0 + b, 1000.0 + b, 2000.0 + b});
    const fs::path p = dir.path / "layout.binary";
    merl::write(p.string(), t);
    const std::vector<double> raw = read_doubles(p);
    for (int ih = 0; ih < 4; ++ih)
        for (int id = 0; id < 5; ++id)
            for (int ip = 0; ip < 6; ++ip) {
                const std::size_t idx = ip + 6 * (id + 5 * ih);
                for (int c = 0; c < 3; ++c)
                    CHECK(static_cast<float>(raw[c * g.bins() + idx] * merl::kScale[c]) == t.at(g.index(ih, id, ip), c));
            }
    std::ifstream f(p, std::ios::binary);
    std::int32_t dims[3];
    f.read(reinterpret_cast<char*>(dims), 12);
    CHECK(dims[0] == 4);
    CHECK(dims[1] == 5);
    CHECK(dims[2] == 6);
}

TEST_CASE("bad MERL files are rejected with the file name and the reason", "[merl][io]") {
    const test::TempDir dir;
    auto rejects = [&](const std::string& name, const std::string& reason_part) {
        const std::string p = (dir.path / name).string();
        try {
            merl::read(p);
            FAIL("accepted " << name);
        } catch (const FormatError& e) {
            const std::string msg = e.what();
            CHECK(msg.find(p) != std::string::npos);
            CHECK(msg.find(reason_part) != std::string::npos);
        }
    };
    write_raw(dir.path / "empty.binary", {}, {});
    rejects("empty.binary", "truncated");
    write_raw(dir.path / "short_header.binary", {90, 90}, {});
    rejects("short_header.binary", "truncated");
    write_raw(dir.path / "truncated.binary", {4, 4, 8}, std::vector<double>(3 * 4 * 4 * 8 - 1, 1.0));
    rejects("truncated.binary", "truncated");
    write_raw(dir.path / "oversized.binary", {4, 4, 8}, payload(4, 4, 8, 1.0), 3);
    rejects("oversized.binary", "oversized");
    write_raw(dir.path / "zero_dim.binary", {0, 90, 180}, {});
    rejects("zero_dim.binary", "out of range");
    write_raw(dir.path / "negative_dim.binary", {90, -90, 180}, payload(1, 1, 1, 1.0));
    rejects("negative_dim.binary", "out of range");
    // Dimensions whose product would overflow 32 bits, or ask for terabytes: refused from the header.
    write_raw(dir.path / "huge_dims.binary", {2147483647, 2147483647, 2147483647}, payload(2, 2, 2, 1.0));
    rejects("huge_dims.binary", "out of range");
    write_raw(dir.path / "big_dims.binary", {4096, 4096, 4096}, payload(2, 2, 2, 1.0));
    rejects("big_dims.binary", "over the limit of 67108864 bins");
    write_raw(dir.path / "all_nan.binary", {2, 2, 4}, payload(2, 2, 4, std::nan("")));
    rejects("all_nan.binary", "no valid");
    write_raw(dir.path / "all_unmeasured.binary", {2, 2, 4}, payload(2, 2, 4, -1.0));
    rejects("all_unmeasured.binary", "no valid");

    CHECK_THROWS_AS(merl::read((dir.path / "missing.binary").string()), IoError);
    CHECK_THROWS_AS(merl::read(dir.path.string()), IoError);
}

TEST_CASE("NaN, Inf and negative MERL values are counted and masked, not clamped", "[merl][io][qemu]") {
    const test::TempDir dir;
    std::vector<double> v = payload(2, 2, 4, 1500.0);
    const std::size_t n = 16;
    v[0] = std::nan("");           // bin 0, red
    v[n + 0] = -1.0;               // bin 0, green: the same bin also negative
    v[1] = INFINITY;               // bin 1
    v[2 * n + 2] = -0.5;           // bin 2, blue
    v[3] = 1e300;                  // bin 3: finite, but overflows f_r in float32
    write_raw(dir.path / "mixed.binary", {2, 2, 4}, v);
    const merl::ReadResult r = merl::read((dir.path / "mixed.binary").string());
    CHECK(r.counts.valid == 12);
    CHECK(r.counts.nan == 1);
    CHECK(r.counts.negative == 2);
    CHECK(r.counts.inf == 2);
    CHECK_FALSE(r.table.valid(0));
    CHECK_FALSE(r.table.valid(2));
    CHECK(std::isnan(r.table.at(2, 2)));
    CHECK(r.table.at(2, 0) == 1.0f);  // the valid channels of a partly invalid bin are kept
    CHECK(r.table.valid(4));
    CHECK(r.table.at(4, 1) == static_cast<float>(1500.0 * merl::kScale[1]));
}

TEST_CASE("writes are atomic: an unfinished write leaves no file behind", "[merl][io]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "out.binary";
    {
        detail::AtomicFile f(p.string());
        f.write("abc", 3);
    }  // destroyed without commit, as when a writer throws
    CHECK(fs::is_empty(dir.path));
    CHECK_THROWS_AS(merl::write((dir.path / "no-such-dir" / "x.binary").string(), Table(GridSpec{2, 2, 2})), IoError);
    CHECK(fs::is_empty(dir.path));

    // A failed overwrite keeps the old file.
    merl::write(p.string(), Table(GridSpec{2, 2, 2}));
    const auto before = fs::file_size(p);
    {
        detail::AtomicFile f(p.string());
        f.write("x", 1);
    }
    CHECK(fs::file_size(p) == before);
}

TEST_CASE("real MERL tables: load, counts, round trip, nearest values", "[merl][io][data]") {
    const std::vector<fs::path> files = test::merl_tables();
    if (files.empty()) {
        WARN("skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    const test::TempDir dir;
    for (const fs::path& p : files) {
        INFO(p);
        const merl::ReadResult r = merl::read(p.string());
        CHECK(r.table.grid() == GridSpec{});
        CHECK(r.counts.valid + r.counts.negative == r.table.bins());
        CHECK(r.counts.valid > r.table.bins() / 2);
        CHECK(r.counts.nan + r.counts.inf == 0);
        merl::write((dir.path / "copy.binary").string(), r.table);
        CHECK(merl::read((dir.path / "copy.binary").string()).table == r.table);

        // Nearest lookup returns the file's value at MERL's bin, rounded through float32.
        const std::vector<double> raw = read_doubles(p);
        const Loaded l = load(p.string(), {BinPosition::Centre, Lookup::Nearest});
        std::mt19937_64 rng(1);
        std::uniform_real_distribution<double> u(0, 1);
        for (int k = 0; k < 2000; ++k) {
            const auto [wi, wo] = from_half_diff({u(rng) * M_PI / 2, 0.0, u(rng) * M_PI / 2, u(rng) * M_PI});
            if (!(wi.z > 0 && wo.z > 0)) continue;
            const HalfDiff hd = to_half_diff(wi, wo);
            const GridSpec g;
            const std::size_t idx = g.index(axis::bin_of(axis::theta_h_to_u(hd.theta_h, 90), 90),
                                            axis::bin_of(axis::theta_d_to_u(hd.theta_d, 90), 90),
                                            axis::bin_of(axis::phi_d_to_u(hd.phi_d, 180), 180));
            const Rgb f = l.brdf->eval(wi, wo);
            for (int c = 0; c < 3; ++c) {
                const double ref = raw[c * g.bins() + idx];
                CHECK(f[c] == (ref < 0 ? 0.0 : static_cast<double>(static_cast<float>(ref * merl::kScale[c]))));
            }
        }
    }
}
