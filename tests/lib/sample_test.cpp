#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "brdfz/formats/io.h"
#include "sample_stats.h"
#include "test_util.h"

using namespace brdfz;

namespace {

TabularBrdf tabulated(double alpha) {
    CoatedDiffuseParams p;
    p.alpha = alpha;
    return TabularBrdf(tabulate(CoatedDiffuse(p)).table);
}

// Bonferroni-corrected 1% level over the five view elevations.
void check_sampler(const Brdf& b, std::size_t samples) {
    test::check_sampler(b, samples, 0.01 / std::size(test::kThetaODeg));
}

}  // namespace

TEST_CASE("tabular sampler: chi-square, normalisation, round trip (glossy and near-specular)", "[sample][tabular]") {
    SECTION("glossy") { check_sampler(tabulated(0.12), 1000000); }
    SECTION("near-specular") { check_sampler(tabulated(0.02), 1000000); }
}

TEST_CASE("tabular sampler: 10^7 random (wo, u) give finite, non-negative pdfs and weights", "[sample][tabular]") {
    const TabularBrdf b = tabulated(0.05);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    std::normal_distribution<double> n;
    std::size_t bad = 0, failed = 0;
    for (int k = 0; k < 10000000; ++k) {
        Vec3 wo = normalize({n(rng), n(rng), n(rng)});
        wo.z = std::fabs(wo.z);
        const BrdfSample s = b.sample(wo, u(rng), u(rng));
        failed += s.pdf == 0;
        bad += !(std::isfinite(s.pdf) && s.pdf >= 0 && std::isfinite(s.weight[0]) && std::isfinite(s.weight[1]) &&
                 std::isfinite(s.weight[2]) && s.weight[0] >= 0);
    }
    CHECK(bad == 0);
    CHECK(failed < 10000000 / 50);  // samples lost below the horizon stay rare
}

TEST_CASE("tabular sampler on real MERL tables", "[sample][data]") {
    const auto files = test::merl_tables();
    if (files.empty()) {
        WARN("skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    for (const auto& path : files) {
        INFO(path);
        const Loaded l = load(path.string());
        for (double deg : {30.0, 80.0}) {
            const Vec3 wo = spherical_direction(deg * M_PI / 180, 1.0);
            CHECK(test::chi2_test(*l.brdf, wo, 300000).p_value > 0.001);
            CHECK(test::pdf_integral(*l.brdf, wo) == Approx(1.0).margin(0.01));
        }
    }
}

TEST_CASE("the chi-square test rejects a sampler whose pdf is wrong", "[sample]") {
    // Draws from the table's sampler but reports the cosine density: must fail.
    class Mismatched final : public Brdf {
    public:
        explicit Mismatched(const TabularBrdf& t) : t_(t) {}
        int channels() const override { return 3; }
        std::size_t nbytes() const override { return 0; }
        std::string describe() const override { return "mismatched"; }

    protected:
        Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return t_.eval(wi, wo); }
        BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override {
            BrdfSample s = t_.sample(wo, u1, u2);
            s.pdf = s.wi.z / M_PI;
            s.weight = {};
            return s;
        }

    private:
        const TabularBrdf& t_;
    };
    const TabularBrdf t = tabulated(0.12);
    CHECK(test::chi2_test(Mismatched(t), spherical_direction(0.5, 0.0), 100000).p_value < 1e-6);
}
