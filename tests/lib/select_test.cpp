#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/scene.h"
#include "brdfz/select.h"
#include "brdfz/tabulate.h"
#include "brdfz/repr/tabular.h"

using namespace brdfz;

namespace {

// f = ρ/π, scaled by `gain`.
AnalyticBrdf lambert(double rho) { return AnalyticBrdf("lambert", {rho, rho, rho}); }

// Isotropic but not reciprocal, as real RGL measurements: brighter where the light is higher than the view.
class Skewed final : public Brdf {
public:
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "skewed lambert"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override {
        const double f = (1.0 + 0.5 * (wi.z - wo.z)) * 0.5 / std::numbers::pi;
        return {f, f, f};
    }
};

// Few pairs: enough to tell a reciprocity error of 0 from one of 0.1.
MetricOptions few_directions() {
    MetricOptions o;
    o.directions = 4096;
    return o;
}

}  // namespace

TEST_CASE("scene pixels of a Lambertian surface are known in closed form", "[scene]") {
    SceneDescription d;
    d.views.push_back(ViewCone{{0, 0, 1}, 60.0, 32});
    const Vec3 light = normalize(Vec3{0.3, 0.1, 1.0});
    d.lights.push_back(Light{light, 0.0, 2.0, 1});
    d.environment = Environment{0.5, 49};
    const Scene scene = build_scene(d);
    REQUIRE(scene.views == 32);
    REQUIRE(scene.samples.size() == 32u * 50u);
    // L = I·cosθ·ρ/π + E·ρ: the cosine-distributed environment samples integrate ρ/π·cos exactly.
    const double rho = 0.6;
    std::vector<double> pixel(scene.views, 0.0);
    for (const SceneSample& s : scene.samples) {
        REQUIRE(s.wi.z > 0.0);
        REQUIRE(s.wo.z > 0.0);
        REQUIRE(s.weight > 0.0);
        REQUIRE(elevation(s.wo) <= 60.0 * std::numbers::pi / 180.0 + 1e-12);
        pixel[s.view] += s.weight * rho / std::numbers::pi;
    }
    for (double p : pixel) CHECK(p == Approx(2.0 * light.z * rho / std::numbers::pi + 0.5 * rho).epsilon(1e-12));
    // Deterministic for a seed, different for another.
    const Scene again = build_scene(d);
    CHECK(again.samples[7].wo.x == scene.samples[7].wo.x);
    d.seed = 2;
    CHECK(build_scene(d).samples[7].wo.x != scene.samples[7].wo.x);
}

TEST_CASE("scene errors are relative and zero for the same BRDF", "[scene]") {
    const Scene scene = build_scene(default_scene());
    const AnalyticBrdf ref = lambert(0.5), brighter = lambert(0.55);
    for (SceneMetric m : {SceneMetric::Image, SceneMetric::Cos, SceneMetric::Log}) CHECK(scene_error(ref, ref, scene, m) == 0.0);
    CHECK(scene_error(ref, brighter, scene, SceneMetric::Image) == Approx(0.1).epsilon(1e-9));
    CHECK(scene_error(ref, brighter, scene, SceneMetric::Cos) == Approx(0.1).epsilon(1e-9));
    CHECK(scene_error(ref, brighter, scene, SceneMetric::Log) > 0.0);
}

TEST_CASE("bad scenes are errors naming the member", "[scene]") {
    SceneDescription d;
    d.views.push_back(ViewCone{});
    CHECK_THROWS_WITH(build_scene(d), Catch::Contains("lights or an environment"));
    d.lights.push_back(Light{{0, 0, 0}});
    CHECK_THROWS_WITH(build_scene(d), Catch::Contains("lights[0].direction"));
    d.lights[0] = Light{{0, 0, 1}, 0.0, -1.0};
    CHECK_THROWS_WITH(build_scene(d), Catch::Contains("lights[0].intensity"));
    d.lights[0] = Light{{0, 0, 1}, 0.0, NAN};
    CHECK_THROWS_AS(build_scene(d), ValueError);
    d.lights[0] = Light{};
    d.views[0].count = 0;
    CHECK_THROWS_WITH(build_scene(d), Catch::Contains("views[0].count"));
    d.views[0] = ViewCone{{0, 0, -1}, 10.0, 4};
    CHECK_THROWS_WITH(build_scene(d), Catch::Contains("below the horizon"));
    SceneDescription pairs;
    pairs.pairs.push_back({{0, 0, 1}, {0, 0.5, -1}, 1.0});
    CHECK_THROWS_WITH(build_scene(pairs), Catch::Contains("pairs[0]"));
    CHECK_THROWS_WITH(build_scene(SceneDescription{}), Catch::Contains("no direction pair"));
}

TEST_CASE("selection keeps the cheapest candidate inside the budget and reports every one", "[select]") {
    const CoatedDiffuse source;
    SelectOptions o;
    o.metric = SceneMetric::Cos;
    o.candidates = {"tabular:res=8x8x16", "tabular:res=16x16x32", "tabular:res=45x45x90", "tabular:res=90x90x180"};
    o.trial.measure_speed = false;
    // Find the errors first, then set a budget between the 2nd and 3rd candidates.
    o.max_error = 1e-12;
    const Selection all = select_representation(source, o);
    REQUIRE(all.tried.size() == 4);
    REQUIRE(all.chosen == -1);
    for (std::size_t k = 1; k < 4; ++k) {
        CHECK(all.tried[k].error < all.tried[k - 1].error);
        CHECK(all.tried[k].trial.bytes > all.tried[k - 1].trial.bytes);
        CHECK_FALSE(all.tried[k].trial.brdf);  // rejected candidates are not kept
    }
    o.max_error = 0.5 * (all.tried[1].error + all.tried[2].error);
    const Selection s = select_representation(source, o);
    REQUIRE(s.chosen == 2);
    CHECK(s.tried.size() == 3);
    CHECK(s.best()->trial.spec == "tabular:res=45x45x90");
    CHECK(s.best()->trial.brdf);
    CHECK_THAT(s.tried[0].reason, Catch::StartsWith("error"));

    // A candidate that fails to build is reported and skipped, not thrown (a misspelt one is thrown:
    // tests/robustness/limits_test.cpp).
    o.candidates = {"pca:basis=no-such-basis.brdfz,k=2", "tabular:res=90x90x180"};
    const Selection f = select_representation(source, o);
    REQUIRE(f.tried.size() == 2);
    CHECK_THAT(f.tried[0].reason, Catch::StartsWith("failed: "));
    CHECK(f.chosen == 1);
    o.max_error = NAN;
    CHECK_THROWS_AS(select_representation(source, o), ValueError);
}

TEST_CASE("a size budget keeps the most accurate candidate within it, with an error budget too the smallest within both", "[select]") {
    const CoatedDiffuse source;
    SelectOptions o;
    o.metric = SceneMetric::Cos;
    o.trial.measure_speed = false;
    // By size; the nearest lookup is as large as the linear one before it and less accurate.
    o.candidates = {"tabular:res=4x4x8,dtype=f16", "tabular:res=16x16x32,dtype=f16",
                    "tabular:res=16x16x32,dtype=f16,lookup=nearest", "tabular:res=45x45x90"};
    o.max_error = 1e-12;
    const Selection all = select_representation(source, o);
    REQUIRE(all.tried.size() == 4);
    const std::size_t mid = all.tried[2].trial.bytes;
    REQUIRE(all.tried[1].trial.bytes == mid);
    REQUIRE(all.tried[2].error > all.tried[1].error);
    REQUIRE(all.tried[1].error < all.tried[0].error);

    o.max_error = std::nullopt;
    o.max_bytes = mid;  // three fit; the most accurate of them is the second, not the last
    const Selection within = select_representation(source, o);
    REQUIRE(within.chosen == 1);
    CHECK(within.tried.size() == 4);  // the search stops at the first larger than the budget
    CHECK_THAT(within.tried[3].reason, Catch::Contains("> size budget"));
    CHECK_THAT(within.tried[2].reason, Catch::Contains("not below"));
    CHECK_THAT(within.tried[0].reason, Catch::Contains("above"));
    CHECK(within.best()->reason == "the most accurate within the size budget");
    CHECK(within.best()->trial.brdf);
    for (std::size_t k : {0, 2, 3}) CHECK_FALSE(within.tried[k].trial.brdf);

    o.max_bytes = mid - 1;  // only the first fits
    const Selection smaller = select_representation(source, o);
    CHECK(smaller.chosen == 0);
    CHECK(smaller.tried.size() == 2);

    // Both budgets: the smallest within both, so the first when its error is allowed...
    o.max_error = all.tried[0].error * 1.01;
    o.max_bytes = all.tried[3].trial.bytes;
    const Selection both = select_representation(source, o);
    CHECK(both.chosen == 0);
    CHECK(both.tried.size() == 1);
    // ...and none when the error asks for more than the size allows.
    o.max_error = 0.5 * (all.tried[1].error + all.tried[3].error);
    o.max_bytes = mid;
    const Selection none = select_representation(source, o);
    CHECK(none.chosen == -1);
    CHECK_THAT(none.tried.back().reason, Catch::Contains("> size budget"));

    o.max_bytes = 0;
    CHECK_THROWS_AS(select_representation(source, o), ValueError);
    o.max_bytes = std::nullopt;
    o.max_error = std::nullopt;
    CHECK_THROWS_AS(select_representation(source, o), ValueError);
}

TEST_CASE("a scene that looks near the normal needs a smaller model than grazing views under the sky", "[select]") {
    // The demo material as a MERL-resolution table: the full-resolution candidate reproduces it exactly.
    const TabularBrdf source(tabulate(CoatedDiffuse{}).table);
    SceneDescription close;
    close.views.push_back(ViewCone{{0, 0, 1}, 15.0, 128});
    close.lights.push_back(Light{{0, 0.1, 1}, 3.0, 1.0, 8});
    SceneDescription grazing;
    grazing.views.push_back(ViewCone{{1, 0, 0.2}, 30.0, 128});
    grazing.environment = Environment{1.0, 64};
    grazing.lights.push_back(Light{{-1, 0, 0.15}, 3.0, 1.0, 8});
    SelectOptions o;
    o.metric = SceneMetric::Image;
    o.max_error = 0.02;
    o.trial.measure_speed = false;
    o.candidates = {"tabular:res=4x4x8", "tabular:res=8x8x16", "tabular:res=16x16x32", "tabular:res=32x32x64",
                    "tabular:res=90x90x180"};
    o.scene = build_scene(close);
    const Selection near_normal = select_representation(source, o);
    o.scene = build_scene(grazing);
    const Selection wide = select_representation(source, o);
    REQUIRE(near_normal.best());
    REQUIRE(wide.best());
    // Close up, 16x16x32 bins are within 2% of the pixels; grazing views under the sky need every bin.
    CHECK(near_normal.best()->trial.bytes < wide.best()->trial.bytes);
    CHECK(near_normal.best()->trial.spec == "tabular:res=16x16x32");
    CHECK(wide.best()->trial.spec == "tabular:res=90x90x180");
}

TEST_CASE("the default candidates are in order of size, so the first within budget is the smallest", "[select]") {
    // A setting again on the warped θh axis (hwarp=auto) has its bytes and follows it; a setting of another
    // kind may have the same bytes.
    // Sizes do not depend on the data: a cheap source gives them, and a model string its parameter count;
    // rgl_svd's, an RGL file's tensors shaped as the RGL-EPFL files' (8 θi slices, 32² rgb).
    const AnalyticBrdf source = lambert(0.5);
    rgl::WriteOptions shape;
    shape.n_theta_i = 8;
    shape.rgb_resolution = 32;
    rgl::Tensors tensors = rgl::derive(source, shape);
    tensors.vndf = rgl::derived_vndf(tensors.theta_i, tensors.ndf, tensors.vndf.rows, tensors.vndf.cols);
    const rgl::RglBrdf rgl_source(std::move(tensors));
    CompressOptions quick;
    std::size_t previous = 0;
    std::string last;
    // Those of a non-reciprocal source too, with φd kept whole.
    const bool whole = GENERATE(false, true);
    for (const std::string& spec : whole ? default_candidates(Skewed(), few_directions()) : default_candidates()) {
        const ReprSpec parsed = ReprSpec::parse(spec);
        // Nor on how factors are fitted: fit=lsq's refit (seconds) is left out, and its weight= with it.
        std::string sized = spec;
        for (const std::string key : {",fit=lsq", ",weight=solid"})
            if (const std::size_t at = sized.find(key); at != std::string::npos) sized.erase(at, key.size());
        const Brdf& from = parsed.kind() == "rgl_svd" ? static_cast<const Brdf&>(rgl_source) : source;
        const std::size_t bytes = parsed.kind() == "analytic" ? Model::parse(parsed.positional()).size() * sizeof(double)
                                                              : compress(from, sized, quick).brdf->nbytes();
        INFO(spec << ": " << bytes << " bytes");
        const bool warped_again = spec == last + ",hwarp=auto";
        const bool other_kind = parsed.kind() != ReprSpec::parse(last.empty() ? spec : last).kind();
        CHECK((warped_again ? bytes == previous : other_kind ? bytes >= previous : bytes > previous));
        previous = bytes;
        last = spec;
    }
}

TEST_CASE("a source above the reciprocity threshold gets candidates that keep phi_d whole", "[select]") {
    const AnalyticBrdf reciprocal = lambert(0.5);
    const Skewed skewed;
    // The threshold sits between what the two measure.
    CHECK(reciprocity_error(reciprocal, few_directions()).cos_rmse_rel.mean < 1e-9);
    CHECK(reciprocity_error(skewed, few_directions()).cos_rmse_rel.mean > 10 * kReciprocityThreshold);
    CHECK(is_reciprocal(reciprocal, few_directions()));
    CHECK_FALSE(is_reciprocal(skewed, few_directions()));
    // Neither is an RGL file, whose own parameterisation the rgl_svd candidates need.
    std::vector<std::string> plain = default_candidates();
    CHECK(std::erase_if(plain, [](const std::string& s) { return s.rfind("rgl_svd:", 0) == 0; }) == 8);
    CHECK(default_candidates(reciprocal, few_directions()) == plain);

    const std::vector<std::string> whole = default_candidates(skewed, few_directions());
    REQUIRE(whole.size() == plain.size());
    std::size_t changed = 0;
    for (std::size_t k = 0; k < whole.size(); ++k) {
        INFO(plain[k] << " -> " << whole[k]);
        const ReprSpec spec = ReprSpec::parse(whole[k]);
        if (spec.kind() == "tabular" || spec.kind() == "svd" || spec.kind() == "nmf") {
            const std::string symmetry = spec.get_string("symmetry", "reciprocal");
            CHECK((symmetry == "bilateral" || symmetry == "none"));
        }
        changed += whole[k] != plain[k];
    }
    CHECK(changed > 0);
    CHECK(std::ranges::find(whole, "tabular:res=90x90x180,symmetry=bilateral") != whole.end());

    CHECK(keep_phi_d_whole({"tabular", "tabular:res=8x8x16", "svd:rank=2,symmetry=reciprocal,dtype=f16",
                            "nmf:rank=2,symmetry=none", "svd:rank=2,symmetry=bilateral", "bivariate:res=32x32",
                            "analytic:lambert+ggx", "nosuch:x=1"}) ==
          std::vector<std::string>{"tabular:symmetry=bilateral", "tabular:res=8x8x16,symmetry=bilateral",
                                   "svd:rank=2,symmetry=bilateral,dtype=f16", "nmf:rank=2,symmetry=none",
                                   "svd:rank=2,symmetry=bilateral", "bivariate:res=32x32", "analytic:lambert+ggx",
                                   "nosuch:x=1"});
    // As many bins, so as many bytes: a list by size stays one.
    CHECK(compress(reciprocal, "tabular:res=8x8x16,symmetry=bilateral").brdf->nbytes() ==
          compress(reciprocal, "tabular:res=8x8x16").brdf->nbytes());
}
