#include <catch2/catch.hpp>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/exr.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

Table random_table(GridSpec g) {
    Table t(g);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    for (std::size_t k = 0; k < 3 * t.bins(); ++k) t.data()[k] = k % 5 ? u(rng) : std::numeric_limits<float>::quiet_NaN();
    const std::uint32_t payload = 0x7fc0beefu;
    std::memcpy(t.data() + 2, &payload, 4);
    return t;
}

// A plain RGB float image, with a brdfz.grid attribute when `grid` is not empty.
void plain_exr(const fs::path& p, int w, int h, const std::string& grid = "") {
    std::vector<float> px(static_cast<std::size_t>(w) * h, 1.0f);
    Imf::Header header(w, h);
    if (!grid.empty()) {
        header.insert("brdfz.grid", Imf::StringAttribute(grid));
        header.insert("brdfz.bin_position", Imf::StringAttribute("centre"));
    }
    Imf::FrameBuffer fb;
    for (const char* name : {"R", "G", "B"}) {
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
        fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(px.data()), sizeof(float), sizeof(float) * w));
    }
    Imf::OutputFile f(p.string().c_str(), header);
    f.setFrameBuffer(fb);
    f.writePixels(h);
}

}  // namespace

TEST_CASE("EXR mosaic round-trips a table bit for bit", "[exr][qemu]") {
    test::TempDir dir;
    for (const GridSpec& g : {GridSpec{7, 5, 11, BinPosition::Start}, GridSpec{90, 90, 180}, GridSpec{1, 1, 1}}) {
        INFO(g.str());
        const Table t = random_table(g);
        const fs::path p = dir.path / "t.exr";
        exr::write(p.string(), t);
        CHECK(exr::read(p.string()) == t);
        // Through load/save by extension too.
        const fs::path q = dir.path / "u.exr";
        save(TabularBrdf(t), q.string());
        const Loaded l = load(q.string());
        CHECK(l.info.format == "exr");
        CHECK(dynamic_cast<const TabularBrdf&>(*l.brdf).table() == t);
    }
    CHECK(exr::tiles_across(180) == 14);
    CHECK(exr::tiles_across(1) == 1);
    CHECK(exr::tiles_across(16) == 4);

    // Anything else is tabulated on the requested grid.
    const fs::path p = dir.path / "cd.exr";
    SaveOptions s;
    s.grid = GridSpec{8, 8, 16};
    const ValidityCounts c = save(CoatedDiffuse(), p.string(), s);
    CHECK(c.valid > 0);
    CHECK(exr::read(p.string()).grid() == *s.grid);
}

TEST_CASE("EXR import refuses images that are not brdfz tables", "[exr]") {
    test::TempDir dir;
    const fs::path p = dir.path / "x.exr";
    plain_exr(p, 12, 8);
    CHECK_THROWS_WITH(exr::read(p.string()), Catch::Contains("no string attribute 'brdfz.grid'"));

    // Attributes that do not match the image, or out of range.
    plain_exr(p, 12, 8, "4x4x4");
    CHECK_THROWS_WITH(exr::read(p.string()), Catch::Contains("brdfz.tiles_across"));
    plain_exr(p, 12, 8, "4x4x0");
    CHECK_THROWS_WITH(exr::read(p.string()), Catch::Contains("out of range"));
    plain_exr(p, 12, 8, "4096x4096x4096");
    CHECK_THROWS_WITH(exr::read(p.string()), Catch::Contains("larger than brdfz reads"));

    const fs::path q = dir.path / "y.exr";
    exr::write(q.string(), random_table({4, 4, 4}));
    std::vector<char> a;
    {
        std::ifstream in(q, std::ios::binary);
        a.assign(std::istreambuf_iterator<char>(in), {});
    }
    // Truncated files and garbage.
    for (std::size_t n : {std::size_t{0}, std::size_t{10}, a.size() / 2, a.size() - 1}) {
        std::ofstream out(p, std::ios::binary | std::ios::trunc);
        out.write(a.data(), static_cast<std::streamsize>(n));
        out.close();
        INFO(n << " bytes");
        CHECK_THROWS_AS(exr::read(p.string()), FormatError);
    }
    // Attributes whose values are not what their types read (OpenEXR reads a type's own layout, not
    // the declared size, and would parse the rest of the header from elsewhere): refused before OpenEXR
    // sees them, by name. The first is a fuzzer's find: a channel list that ends early, followed within
    // its declared size by what OpenEXR took for a 1 GB string attribute.
    const auto u32 = [](std::uint32_t n) {
        return std::string{static_cast<char>(n & 0xff), static_cast<char>(n >> 8 & 0xff),
                           static_cast<char>(n >> 16 & 0xff), static_cast<char>(n >> 24 & 0xff)};
    };
    const std::string channel = std::string("R\0", 2) + u32(2) + std::string(4, '\0') + u32(1) + u32(1);
    const std::string hidden = channel + std::string(1, '\0') + std::string("huge\0string\0", 12) + u32(1u << 30);
    for (const auto& [type, value] : std::vector<std::pair<std::string, std::string>>{
             {"chlist", hidden}, {"float", std::string(5, '\0')}, {"preview", std::string(8, '\0')},
             {"stringvector", u32(100) + "abc"}}) {
        std::string b(a.begin(), a.end());
        b.insert(8, "extra" + std::string(1, '\0') + type + std::string(1, '\0') + u32(value.size()) + value);
        std::ofstream out(p, std::ios::binary | std::ios::trunc);
        out.write(b.data(), static_cast<std::streamsize>(b.size()));
        out.close();
        INFO(type);
        CHECK_THROWS_WITH(exr::read(p.string()), Catch::Contains("attribute 'extra' of type '" + type + "'"));
    }
    CHECK_THROWS_AS(exr::read((dir.path / "missing.exr").string()), IoError);
    CHECK_THROWS_AS(exr::write((dir.path / "no" / "dir.exr").string(), random_table({2, 2, 2})), IoError);
}
