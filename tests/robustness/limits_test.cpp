// Bounds checked before work (grid sizes, fit starts), specs and candidates refused as typed, metrics
// that cannot be measured, and messages that stay one printable line.
#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>
#include <limits>
#include <string>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/merl.h"
#include "brdfz/formats/scene_json.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/spec.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/select.h"
#include "brdfz/tabulate.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

const AnalyticBrdf& material() {
    static const AnalyticBrdf m("lambert+ggx", {0.3, 0.4, 0.5, 0.2, 0.2, 0.2, 0.3, 0.04});
    return m;
}

Table table_on(GridSpec grid) {
    TabulateOptions o;
    o.grid = grid;
    return tabulate(material(), o).table;
}

}  // namespace

TEST_CASE("robustness: grids beyond 2^26 bins are refused before allocating, with the bytes", "[robustness][limits]") {
    const GridSpec largest{256, 256, 1024}, over{1024, 1024, 1024}, huge{4096, 4096, 4096};
    CHECK_NOTHROW(largest.validate());  // exactly 2^26 bins
    CHECK_THROWS_WITH(over.validate(), Catch::Contains("1073741824 bins, a float32 table of 12884901888 bytes, over the "
                                                       "limit of 67108864 bins (805306368 bytes)"));
    CHECK_THROWS_WITH(Table(huge), Catch::Contains("over the limit"));
    CHECK_THROWS_WITH(compress(material(), "tabular:res=1024x1024x1024"), Catch::Contains("12884901888 bytes"));
    CHECK_THROWS_WITH(compress(material(), "svd:rank=2,res=4096x4096x4096"), Catch::Contains("over the limit"));

    // A MERL header of 1024x1024x512, refused by its dimensions before the file's size is considered.
    const test::TempDir dir;
    const fs::path p = dir.path / "big.binary";
    {
        std::ofstream out(p, std::ios::binary);
        const std::int32_t dims[3] = {1024, 1024, 512};
        out.write(reinterpret_cast<const char*>(dims), sizeof dims);
    }
    CHECK_THROWS_WITH(merl::read(p.string()), Catch::Contains("MERL dimensions: grid 1024x1024x512: 536870912 bins, "
                                                               "a float32 table of 6442450944 bytes"));
}

TEST_CASE("robustness: a bare word in a spec is refused as a misspelt key is", "[robustness][spec]") {
    for (const char* spec : {"tabular:wibble", "svd:foo", "bivariate:dtypes"}) {
        INFO(spec);
        const std::string kind = ReprSpec::parse(spec).kind(), word = std::string(spec).substr(kind.size() + 1);
        CHECK_THROWS_AS(check_spec(spec), SpecError);
        CHECK_THROWS_WITH(compress(material(), spec), kind + ": unknown option(s) " + word);
        CHECK_THROWS_WITH(compress(material(), kind + ":" + word + "=1"), kind + ": unknown option(s) " + word);
    }
    for (const char* spec : {"tabular:res", "nmf:rank"}) {  // a key without its value
        const std::string kind = ReprSpec::parse(spec).kind(), key = std::string(spec).substr(kind.size() + 1);
        CHECK_THROWS_WITH(compress(material(), spec), kind + ": option " + key + " needs a value (" + key + "=...)");
    }
    CHECK_THROWS_WITH(check_spec("tabular:res=8x8x16,wibble"), Catch::Contains("expected KEY=VALUE"));
    CHECK_THROWS_WITH(check_spec("tabular:res=8x8x16,rse=2"), "tabular: unknown option(s) rse");
    CHECK_NOTHROW(check_spec("analytic:lambert,starts=1"));  // the one kind with a positional part
    CHECK_NOTHROW(check_spec("tabular:res=0x1x1"));           // values are the builder's to check
}

TEST_CASE("robustness: a misspelt candidate is an error, not a rejected candidate", "[robustness][select]") {
    const TabularBrdf table(table_on(GridSpec{8, 8, 16}));
    SelectOptions o;
    o.max_error = 1e-9;
    int tried = 0;
    o.on_candidate = [&](const Candidate&) { ++tried; };
    o.candidates = {"tabular:res=4x4x8", "bogus:res=4x4x8"};
    CHECK_THROWS_AS(select_representation(table, o), SpecError);
    o.candidates = {"tabular:res=4x4x8", "tabular:rse=4x4x8"};
    CHECK_THROWS_WITH(select_representation(table, o), "tabular: unknown option(s) rse");
    CHECK(tried == 0);  // found before anything is built
    o.candidates = {"tabular:res=4x4x8", "tabular:res=0x4x8"};  // a value: refused by its builder
    CHECK_THROWS_AS(select_representation(table, o), SpecError);
    CHECK(tried == 1);
    o.candidates = {"tabular:res=4x4x8"};
    CHECK_FALSE(select_representation(table, o).best());  // over budget: a result, not an error
}

TEST_CASE("robustness: fit starts are capped as the spec parser caps them", "[robustness][fit]") {
    const TabularBrdf table(table_on(GridSpec{8, 8, 16}));
    FitOptions o;
    o.starts = FitOptions::kMaxStarts + 1;
    CHECK_THROWS_WITH(fit(table, "lambert", o), "fit: starts=1001 is outside [1, 1000]");
    o.starts = 1000000;
    CHECK_THROWS_AS(fit(table, "lambert", o), ValueError);
    CHECK_THROWS_WITH(compress(table, "analytic:lambert,starts=1001"), Catch::Contains("outside [1, 1000]"));
}

TEST_CASE("robustness: a whole number beyond a key's range is out of range, not 'not an integer'",
          "[robustness][spec]") {
    CHECK_THROWS_WITH(compress(material(), "svd:iterations=4000000000"), "svd: iterations=4000000000 is outside [1, 100000]");
    CHECK_THROWS_WITH(compress(material(), "analytic:lambert,seed=99999999999"),
                      "analytic: seed=99999999999 is outside [0, 1073741824]");
    CHECK_THROWS_WITH(compress(material(), "analytic:lambert,seed=-99999999999"), Catch::Contains("is outside [0, "));
    CHECK_THROWS_WITH(compress(material(), "svd:rank=4x"), "svd: rank='4x' is not an integer");
}

TEST_CASE("robustness: phih asks for at most the slices a .brdfz file holds, refused before any work",
          "[robustness][spec][limits]") {
    const test::TempDir dir;
    CHECK_THROWS_WITH(compress(material(), "tabular:res=2x2x4,phih=250"), "tabular: phih=250 is outside [1, 249]");
    CHECK_THROWS_WITH(compress(material(), "svd:rank=1,res=2x2x4,phih=84"), "svd: phih=84 is outside [1, 83]");
    CHECK_THROWS_WITH(compress(material(), "nmf:rank=1,res=2x2x4,phih=4096"), "nmf: phih=4096 is outside [1, 83]");
    // The largest of each is stored and read back (colour=shared: the most datasets per slice).
    for (const auto& [spec, slices] : {std::pair{"tabular:res=2x2x4,phih=249", 249u},
                                        std::pair{"svd:rank=1,res=2x2x4,phih=83,colour=shared", 83u}}) {
        INFO(spec);
        const fs::path p = dir.path / "phih.brdfz";
        save(*compress(material(), spec).brdf, p.string());
        CHECK(load(p.string()).info.dims.front() == slices);
    }
}

TEST_CASE("robustness: a file against itself is exactly 0, a reference with no reflectance is an error",
          "[robustness][metrics]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "m.binary";
    merl::write(p.string(), table_on(GridSpec{16, 16, 32}));
    for (Lookup lookup : {Lookup::Linear, Lookup::Nearest}) {
        const Loaded a = load(p.string(), {BinPosition::Centre, lookup}), b = load(p.string(), {BinPosition::Centre, lookup});
        const Metrics m = compare(*a.brdf, *b.brdf);
        CHECK(m.samples > 0);
        CHECK(m.cos_rmse.mean == 0.0);
        CHECK(m.cos_rmse_rel.mean == 0.0);
        CHECK(m.log_rmse.mean == 0.0);
        CHECK(m.cbrt_rmse.mean == 0.0);
    }
    // All zero (or negative, taken as 0): cos_rmse_rel would be inf.
    Table zero(GridSpec{8, 8, 16});
    for (std::size_t b = 0; b < zero.bins(); ++b) zero.set(b, {0.0, 0.0, 0.0});
    CHECK_THROWS_WITH(compare(TabularBrdf(zero), material()), Catch::Contains("zero or negative at every sample"));
    MeasurementSet negative;
    negative.samples.push_back({{0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}, {-0.1, -0.2, -0.3}});
    CHECK_THROWS_WITH(compare(negative, material()), Catch::Contains("zero or negative at every sample"));
}

TEST_CASE("robustness: a scene value refused after parsing names the scene file", "[robustness][errors]") {
    const test::TempDir dir;
    const fs::path p = dir.path / "scene.json";
    std::ofstream(p) << R"({"format": "brdfz-scene", "version": 1, "lights": [{"direction": [0, 0, 1], "intensity": -1}],
                           "views": [{"axis": [0, 0, 1], "max_angle_deg": 30, "count": 4}]})";
    CHECK_THROWS_AS(scene_json::load(p.string()), ValueError);
    CHECK_THROWS_WITH(scene_json::load(p.string()), p.string() + ": scene: lights[0].intensity must be finite and >= 0");
}

TEST_CASE("robustness: messages are one printable line whatever bytes they quote", "[robustness][errors]") {
    CHECK(printable("plain text, é and ✓") == "plain text, é and ✓");
    CHECK(printable("a\nb\tc\x1b[31m") == "a\\x0ab\\x09c\\x1b[31m");
    CHECK(printable("\xff\xfe") == "\\xff\\xfe");
    CHECK(printable("\xc2\x9b") == "\\xc2\\x9b");          // C1 control (CSI) in UTF-8
    CHECK(printable("\xe0\x80\xaf") == "\\xe0\\x80\\xaf");  // overlong
    CHECK(printable("\xed\xa0\x80") == "\\xed\\xa0\\x80");  // surrogate
    CHECK(printable("caf\xc3") == "caf\\xc3");              // cut short
    CHECK(std::string(ValueError("field 'x\ny'\x1b").what()) == "field 'x\\x0ay'\\x1b");  // every exception's message

    // A tensor_file whose field name holds control bytes and invalid UTF-8.
    const test::TempDir dir;
    const fs::path p = dir.path / "names.bsdf";
    {
        std::string b("tensor_file\0\x01\x00", 14);
        const std::uint32_t n = 1;
        b.append(reinterpret_cast<const char*>(&n), 4);
        const std::string name = "\x1b]0;pwned\x07\xff";
        const std::uint16_t len = static_cast<std::uint16_t>(name.size()), rank = 1;
        b.append(reinterpret_cast<const char*>(&len), 2).append(name);
        b.append(reinterpret_cast<const char*>(&rank), 2).push_back(char{99});  // an unknown dtype
        std::ofstream(p, std::ios::binary) << b;
    }
    try {
        load(p.string());
        FAIL("loaded");
    } catch (const FormatError& e) {
        const std::string what = e.what();
        CHECK_THAT(what, Catch::Contains("field '\\x1b]0;pwned\\x07\\xff': unknown dtype code 99"));
        CHECK(what.find('\x1b') == std::string::npos);
    }
}
