#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/model_json.h"
#include "brdfz/formats/scene_json.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "test_util.h"

using namespace brdfz;

namespace {

void write_text(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

const char* kGood = R"({
  "format": "brdfz-analytic",
  "version": 1,
  "model": "lambert+ggx",
  "parameters": {"lambert.rho_r": 0.2, "lambert.rho_g": 0.3, "lambert.rho_b": 0.4,
    "ggx.ks_r": 1, "ggx.ks_g": 1, "ggx.ks_b": 1, "ggx.alpha": 0.2, "ggx.f0": 4e-2},
  "provenance": {"source": "caf\u00e9 \ud83d\ude00", "nested": [1, {"a": null}, true]}
})";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
    const auto at = s.find(from);
    REQUIRE(at != std::string::npos);
    return s.replace(at, from.size(), to);
}

}  // namespace

TEST_CASE("model files round-trip bit for bit and load by extension", "[json][io]") {
    test::TempDir dir;
    const auto path = (dir.path / "m.json").string();
    const AnalyticBrdf model("lambert+ggx+lafortune2", {0.1, 0.2, 0.3, 0.9, 0.8, 0.7, 0.123456789012345678, 0.04,
                                                        1.0 / 3.0, 0.5, 0.5, -0.9, 0.8, 12.5,
                                                        0.1, 0.1, 0.1, 1, 1, 3});
    model_json::write(path, model, {{"source", std::string("a \"quoted\"\nname")}, {"cost", 1.5}});
    const AnalyticBrdf back = model_json::read(path);
    CHECK(back.model().text() == model.model().text());
    REQUIRE(back.params().size() == model.params().size());
    for (std::size_t i = 0; i < model.params().size(); ++i) CHECK(back.params()[i] == model.params()[i]);
    // No temporary left beside the file.
    int files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path)) files += e.is_regular_file();
    CHECK(files == 1);

    const Loaded loaded = load(path);
    CHECK(loaded.info.format == "json");
    CHECK(loaded.brdf->nbytes() == model.params().size() * sizeof(double));
    const Vec3 wi = normalize({0.3, 0.1, 0.9}), wo = normalize({-0.2, 0.4, 0.8});
    CHECK(loaded.brdf->eval(wi, wo) == model.eval(wi, wo));
    // save() writes analytic models and refuses anything else.
    save(*loaded.brdf, (dir.path / "again.json").string());
    CHECK(model_json::read((dir.path / "again.json").string()).params()[6] == model.params()[6]);

    write_text(dir.path / "good.json", kGood);
    CHECK(model_json::read((dir.path / "good.json").string()).params()[7] == 0.04);
}

TEST_CASE("the model-file reader rejects every malformed or invalid file, naming it", "[json][io]") {
    test::TempDir dir;
    const std::pair<std::string, std::string> cases[] = {
        {"", "end of file"},
        {"[]", "top level"},
        {std::string(kGood) + "x", "after the JSON value"},
        {replaced(kGood, "\"version\": 1", "\"version\": 2"), "unsupported version"},
        {replaced(kGood, "\"version\": 1", "\"version\": \"1\""), "must be a number"},
        {replaced(kGood, "brdfz-analytic", "brdfz-table"), "not an analytic model file"},
        {replaced(kGood, "lambert+ggx", "lambert+gxx"), "unknown lobe 'gxx'"},
        {replaced(kGood, ", \"ggx.f0\": 4e-2", ""), "missing parameter \"ggx.f0\""},
        {replaced(kGood, "\"ggx.f0\"", "\"ggx.f1\""), "unknown parameter \"ggx.f1\""},
        {replaced(kGood, "\"ggx.alpha\": 0.2", "\"ggx.alpha\": 0.2, \"ggx.alpha\": 0.3"), "duplicate key"},
        {replaced(kGood, "4e-2", "NaN"), "expected a JSON value"},
        {replaced(kGood, "4e-2", "null"), "must be a number"},
        {replaced(kGood, "4e-2", "1e999"), "out of the range"},
        {replaced(kGood, "4e-2", "1.5"), "outside its bounds"},
        {replaced(kGood, "4e-2", "04"), "expected '}'"},  // no leading zeros
        {replaced(kGood, "4e-2", ".5"), "expected a JSON value"},
        {replaced(kGood, "\"ggx.f0\": 4e-2", "\"ggx.f0\": 0.04,"), "expected a string key"},
        {replaced(kGood, "\"model\"", "\"modle\""), "unknown member \"modle\""},
        {replaced(kGood, "\\ud83d\\ude00", "\\ud83d"), "unpaired surrogate"},
        {replaced(kGood, "caf", "c\tf"), "control character"},
        {replaced(kGood, "{\"a\": null}", std::string(40, '[') + std::string(40, ']')), "nested deeper"},
    };
    int k = 0;
    for (const auto& [text, why] : cases) {
        const auto path = (dir.path / ("bad" + std::to_string(k++) + ".json")).string();
        write_text(path, text);
        INFO(text);
        CHECK_THROWS_AS(model_json::read(path), FormatError);
        CHECK_THROWS_WITH(model_json::read(path), Catch::StartsWith(path) && Catch::Contains(why));
    }
    const auto big = (dir.path / "big.json").string();
    write_text(big, std::string(model_json::kMaxFileBytes + 1, ' '));
    CHECK_THROWS_WITH(model_json::read(big), Catch::Contains("larger than a model file"));
    CHECK_THROWS_AS(model_json::read((dir.path / "missing.json").string()), IoError);
    CHECK_THROWS_AS(save(CoatedDiffuse(), (dir.path / "x.json").string()), UnsupportedError);
}

TEST_CASE("scene files: counts and seeds that are not whole numbers in range are refused, naming the member",
          "[json][io]") {
    test::TempDir dir;
    const auto path = (dir.path / "scene.json").string();
    // Beyond long long's range (found by the fuzzer), negative, fractional, above the limit.
    for (const char* seed : {"4e107", "-4e107", "-1", "2.5", "2e9"}) {
        INFO(seed);
        write_text(path, std::string(R"({"format": "brdfz-scene", "version": 1, "seed": )") + seed + "}");
        CHECK_THROWS_WITH(scene_json::read(path), Catch::Contains("scene.seed: must be a whole number"));
    }
    write_text(path, R"({"format": "brdfz-scene", "version": 1, "views": [{"count": 1e300}]})");
    CHECK_THROWS_WITH(scene_json::read(path), Catch::Contains("views[0].count: must be a whole number"));
    write_text(path, R"({"format": "brdfz-scene", "version": 1, "seed": 12345, "views": [{"count": 7}], "lights": [{}]})");
    const SceneDescription d = scene_json::read(path);
    CHECK(d.seed == 12345);
    REQUIRE(d.views.size() == 1);
    CHECK(d.views[0].count == 7);
}
