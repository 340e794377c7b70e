#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/repr/analytic/catalogue.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/sample/lobes.h"
#include "sample_stats.h"

using namespace brdfz;

namespace {

struct Case {
    std::string model;
    std::vector<double> params;
};

// Every family, rough and sharp where it has a roughness, and mixes of families.
const std::vector<Case>& cases() {
    static const std::vector<Case> c = {
        {"lambert", {0.5, 0.4, 0.3}},
        {"blinn_phong", {0.8, 0.7, 0.6, 0.5}},
        {"blinn_phong", {0.8, 0.7, 0.6, 2000}},
        {"ward", {0.8, 0.7, 0.6, 0.4}},
        {"ward", {0.8, 0.7, 0.6, 0.03}},
        {"ggx", {0.9, 0.8, 0.7, 0.6, 0.04}},
        {"ggx", {0.9, 0.8, 0.7, 0.03, 0.04}},
        {"ggx_dielectric", {1, 1, 1, 0.2, 1.5}},
        {"ggx_conductor", {1, 1, 1, 0.3, 0.18, 0.42, 1.37, 3.42, 2.35, 1.77}},
        {"ggx_sep", {1, 1, 1, 1.0, 0.5}},
        {"ggx_dielectric_sep", {1, 1, 1, 0.1, 1.3}},
        {"ggx_conductor_sep", {1, 1, 1, 0.15, 0.2, 0.9, 1.1, 3.9, 2.4, 2.2}},
        {"beckmann", {0.9, 0.8, 0.7, 0.6, 0.04}},
        {"beckmann", {0.9, 0.8, 0.7, 0.03, 0.04}},
        {"beckmann_dielectric", {1, 1, 1, 1.0, 1.5}},
        {"beckmann_conductor", {1, 1, 1, 0.2, 0.18, 0.42, 1.37, 3.42, 2.35, 1.77}},
        {"ggx_aniso", {1, 1, 1, 0.4, 0.05, 0.1}},
        {"ashikhmin_shirley", {0.5, 0.4, 0.3, 0.1, 0.1, 0.1, 200, 10}},
        {"lafortune", {0.8, 0.7, 0.6, -1, 1, 20}},    // Phong around the mirror direction
        {"lafortune", {0.8, 0.7, 0.6, 0.9, 0.8, 3}},  // retro-reflective
        {"lafortune", {0.8, 0.7, 0.6, 0, 1, 0.5}},    // broad, toward the normal
        {"lambert+ggx", {0.2, 0.3, 0.4, 0.9, 0.9, 0.9, 0.1, 0.04}},
        {"lambert+beckmann+blinn_phong", {0.1, 0.1, 0.1, 0.5, 0.5, 0.5, 0.3, 0.04, 0.3, 0.3, 0.3, 300}},
        {"lafortune3", {0.3, 0.3, 0.3, -1, 1, 50, 0.2, 0.2, 0.2, 1, 1, 5, 0.1, 0.1, 0.1, -0.5, 0.2, 2}},
        {"ggx+ggx", {0.5, 0.5, 0.5, 0.02, 0.04, 0.5, 0.5, 0.5, 0.5, 0.04}},
    };
    return c;
}

Vec3 random_upper(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    Vec3 v = normalize({n(rng), n(rng), n(rng)});
    v.z = std::fabs(v.z);
    return v;
}

std::vector<double> random_params(const Model& m, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> p(m.size());
    for (std::size_t i = 0; i < m.size(); ++i) {
        const ParamSpec& s = m.spec(i);
        // A quarter of the draws sit on a bound, where samplers meet their extremes (α = 0.001, n = 1e5).
        const double x = u(rng) < 0.25 ? std::round(u(rng)) : u(rng);
        p[i] = s.kind == ParamKind::LogScale ? s.lo * std::pow(s.hi / s.lo, x) : s.lo + (s.hi - s.lo) * x;
    }
    return p;
}

}  // namespace

TEST_CASE("every lobe family has a tested sampler", "[sample][analytic]") {
    std::set<std::string> tested;
    for (const Case& c : cases()) {
        const Model m = Model::parse(c.model);
        for (const Model::Term& t : m.terms()) tested.insert(std::string(t.type->name));
    }
    for (const LobeType& t : lobe_types()) {
        INFO(t.name);
        CHECK(tested.count(std::string(t.name)) == 1);
    }
}

namespace {

// Family F's header sample and pdf are what the mixture draws with: the catalogue's sampler points at
// them, and a one-lobe model's draw is F::sample's direction (folded to the upper hemisphere) with the
// folded F::pdf, bit for bit.
template <typename F>
void check_header_sampler(std::size_t index, std::mt19937_64& rng) {
    const LobeType& type = lobe_types()[index];
    INFO(type.name);
    REQUIRE(type.name == F::name);
    CHECK(lobe_sampler(type).sample == &F::sample);
    CHECK(lobe_sampler(type).pdf == &F::pdf);
    std::vector<double> p;
    for (const ParamSpec& s : F::params) p.push_back(s.init);
    const AnalyticBrdf b{std::string(F::name), p};
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::size_t drawn = 0;
    for (int i = 0; i < 500; ++i) {
        const Vec3 wo = random_upper(rng);
        const double u1 = u(rng), u2 = u(rng);
        const BrdfSample s = b.sampler().sample(wo, u1, u2);
        Vec3 w = F::sample(p.data(), wo, u1, u2);
        w.z = std::fabs(w.z);
        const double pdf = F::pdf(p.data(), wo, w) + F::pdf(p.data(), wo, {w.x, w.y, -w.z});
        if (s.pdf == 0.0) continue;
        ++drawn;
        REQUIRE(test::same_bits(s.wi.x, w.x));
        REQUIRE(test::same_bits(s.wi.y, w.y));
        REQUIRE(test::same_bits(s.wi.z, w.z));
        REQUIRE(test::same_bits(s.pdf, pdf));
    }
    CHECK(drawn > 400);
}

template <typename... Families>
void check_header_samplers(LobeList<Families...>) {
    std::mt19937_64 rng(31);
    std::size_t index = 0;
    (check_header_sampler<Families>(index++, rng), ...);
}

}  // namespace

TEST_CASE("every lobe family samples with its header's sample and pdf", "[sample][analytic]") {
    check_header_samplers(AllLobes{});
}

// Every case: χ² of batch draws (the mixture's block kernel, LobeMixture::sample_block), normalisation and
// round trip at 0/30/60/80/87 deg, and batch = one call, bit for bit.
void check_samplers(std::size_t samples, test::Chi2Setting chi2) {
    // Bonferroni over every case and angle: a 1% chance in all that any check fails by chance.
    const double p_min = 0.01 / (cases().size() * std::size(test::kThetaODeg));
    for (const Case& c : cases()) {
        const AnalyticBrdf b(c.model, c.params);
        INFO(b.describe());
        test::check_sampler(b, samples, p_min, chi2);
        test::check_batch_bits(b);
    }
}

TEST_CASE("analytic samplers: chi-square, normalisation, round trip at 0/30/60/80/87 deg, batch = one call",
          "[sample][analytic][chi2][heavy]") {
    check_samplers(200000, {test::Draws::Batch, 32, test::kSmoothPoints});
}

TEST_CASE("analytic samplers: the same checks with fewer draws", "[sample][analytic][chi2][light]") {
    check_samplers(20000, {test::Draws::Batch, 16, test::kSmoothPoints});
}

namespace {

// n random (wo, u, parameters) over every lobe and a mixture: finite, non-negative pdfs and weights.
void check_random_draws(std::size_t n) {
    std::vector<std::string> models;
    for (const LobeType& t : lobe_types()) models.emplace_back(t.name);
    models.push_back("lambert+ggx+beckmann+lafortune2");
    const std::size_t per_model = n / models.size(), per_params = std::min<std::size_t>(20000, per_model);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    std::size_t bad = 0, mismatched = 0, failed = 0, total = 0;
    for (const std::string& name : models) {
        const Model model = Model::parse(name);
        for (std::size_t start = 0; start < per_model; start += per_params) {
            const AnalyticBrdf b(model, random_params(model, rng));
            for (std::size_t k = 0; k < per_params; ++k, ++total) {
                Vec3 wo = random_upper(rng);
                if (k % 1000 == 0) wo = k % 2000 ? Vec3{0, 0, 1} : normalize({1, 0, 1e-9});  // pole, grazing
                const double u1 = k % 997 == 0 ? 0.0 : u(rng), u2 = k % 991 == 0 ? std::nextafter(1.0, 0.0) : u(rng);
                const BrdfSample s = b.sample(wo, u1, u2);
                failed += s.pdf == 0;
                bad += !(std::isfinite(s.pdf) && s.pdf >= 0 && std::isfinite(s.weight[0]) && std::isfinite(s.weight[1]) &&
                         std::isfinite(s.weight[2]) && s.weight[0] >= 0 && s.weight[1] >= 0 && s.weight[2] >= 0);
                if (k % 64 == 0 && s.pdf > 0) {
                    const double p = b.pdf(wo, s.wi);
                    mismatched += !(std::fabs(p - s.pdf) <= 1e-9 * s.pdf);
                }
            }
        }
    }
    CHECK(total >= n * 99 / 100);
    CHECK(bad == 0);
    CHECK(mismatched == 0);
    CHECK(failed < total / 1000);  // folding keeps draws above the horizon: failures are rounding only
}

}  // namespace

TEST_CASE("analytic samplers: 10^7 random (wo, u, parameters) give finite, non-negative pdfs and weights",
          "[sample][analytic][robust][heavy]") {
    check_random_draws(10000000);
}

// The sanitizers' share of the test above: one parameter set per model.
TEST_CASE("analytic samplers: 10^5 random (wo, u, parameters) give finite, non-negative pdfs and weights",
          "[sample][analytic][robust][light]") {
    check_random_draws(100000);
}

TEST_CASE("analytic samplers: lobes are chosen in proportion to their albedo", "[sample][analytic]") {
    const AnalyticBrdf b("lambert+ggx", {0.3, 0.3, 0.3, 0.8, 0.8, 0.8, 0.2, 0.04});
    const AnalyticBrdf diffuse("lambert", {0.3, 0.3, 0.3}), glossy("ggx", {0.8, 0.8, 0.8, 0.2, 0.04});
    for (double deg : {0.0, 45.0, 80.0}) {
        INFO("theta_o = " << deg);
        const double t = deg * M_PI / 180;
        const double a = directional_albedo(diffuse, t)[0], g = directional_albedo(glossy, t)[0];
        const std::vector<double> w = b.sampler().weights(spherical_direction(t, 0.0));
        REQUIRE(w.size() == 2);
        CHECK(w[0] + w[1] == Approx(1.0).epsilon(1e-12));
        // Interpolated between estimates from 256 stratified samples at 16 nodes: a few percent.
        CHECK(w[1] == Approx(g / (a + g)).epsilon(0.05));
    }
    // A black lobe is never chosen; a black model falls back to cosine sampling.
    const AnalyticBrdf half_black("lambert+ggx", {0, 0, 0, 0.8, 0.8, 0.8, 0.2, 0.04});
    CHECK(half_black.sampler().weights({0, 0, 1})[0] == 0.0);
    const AnalyticBrdf black("ggx", {0, 0, 0, 0.2, 0.04});
    const Vec3 wo = normalize({0.3, 0.1, 0.8});
    const BrdfSample s = black.sample(wo, 0.3, 0.7);
    CHECK(s.pdf == Approx(s.wi.z / M_PI));
    CHECK(s.weight == Rgb{0, 0, 0});
}

TEST_CASE("analytic samplers: sampled albedo matches quadrature, with far less variance than cosine sampling",
          "[sample][analytic][heavy]") {
    for (const Case& c : cases()) {
        const AnalyticBrdf b(c.model, c.params);
        INFO(b.describe());
        for (double deg : {20.0, 75.0}) {
            INFO("theta_o = " << deg);
            const double t = deg * M_PI / 180;
            const SampledAlbedo s = sampled_albedo(b, t, 20000, 3);
            const Rgb q = directional_albedo(b, t, {512, 64, 8});
            for (int ch = 0; ch < 3; ++ch) CHECK(std::fabs(s.mean[ch] - q[ch]) <= 5 * s.stderr_[ch] + 1e-3 * q[ch]);
        }
    }
    // Importance sampling pays on a sharp lobe: the albedo estimate's standard error against a
    // cosine-weighted estimate of the same integral (f·cos/pdf with pdf = cosθi/π, i.e. π f).
    const AnalyticBrdf sharp("ggx", {1, 1, 1, 0.05, 0.04});
    const Vec3 wo = spherical_direction(0.5, 0.0);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    double s1 = 0, s2 = 0, c1 = 0, c2 = 0;
    const int n = 100000;
    for (int k = 0; k < n; ++k) {
        const double w = sharp.sample(wo, u(rng), u(rng)).weight[0];
        s1 += w, s2 += w * w;
        const double r = std::sqrt(u(rng)), phi = 2 * M_PI * u(rng);
        const Vec3 wi{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::fmax(0.0, 1 - r * r))};
        const double cw = M_PI * sharp.eval(wi, wo)[0];
        c1 += cw, c2 += cw * cw;
    }
    const double var_lobe = s2 / n - (s1 / n) * (s1 / n), var_cos = c2 / n - (c1 / n) * (c1 / n);
    CHECK(var_lobe * 1000 < var_cos);
}
