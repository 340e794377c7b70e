#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/sample/factor_sampler.h"
#include "brdfz/tabulate.h"
#include "sample_stats.h"
#include "test_util.h"

using namespace brdfz;
using test::check_sampler;

// The factor sampler's density is smooth across the χ² cells (test::kSmoothPoints).
constexpr test::Chi2Setting kFactorChi2{test::Draws::OneAtATime, 32, test::kSmoothPoints};

namespace {

Table coated(const GridSpec& g, double alpha) {
    CoatedDiffuseParams p;
    p.alpha = alpha;
    TabulateOptions o;
    o.grid = g;
    return tabulate(CoatedDiffuse(p), o).table;
}

FactorOptions options(FactorMethod method, int rank, FactorSpace space, FactorLayout layout, FactorColour colour,
                      int iterations = 30) {
    FactorOptions o;
    o.method = method;
    o.rank = rank;
    o.space = space;
    o.layout = layout;
    o.colour = colour;
    o.max_iterations = iterations;
    return o;
}

std::string label(const Factors& f) {
    return std::string(factor_method_name(f.method)) + " rank " + std::to_string(f.rank) + " " +
           factor_space_name(f.space) + " " + factor_layout_name(f.layout) + " " + factor_colour_name(f.colour);
}

// Random (wo, u) over the upper hemisphere: counts of non-finite or negative pdfs and weights, and of
// failed draws.
struct RandomDraws {
    std::size_t bad = 0, failed = 0;
};
RandomDraws random_draws(const Brdf& b, int n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    std::normal_distribution<double> g;
    RandomDraws r;
    for (int k = 0; k < n; ++k) {
        Vec3 wo = normalize({g(rng), g(rng), g(rng)});
        wo.z = std::fabs(wo.z);
        const BrdfSample s = b.sample(wo, u(rng), u(rng));
        r.failed += s.pdf == 0;
        r.bad += !(std::isfinite(s.pdf) && s.pdf >= 0 && std::isfinite(s.weight[0]) && std::isfinite(s.weight[1]) &&
                   std::isfinite(s.weight[2]) && s.weight[0] >= 0 && s.weight[1] >= 0 && s.weight[2] >= 0);
    }
    return r;
}

// A FactorSampler as a Brdf (f = 1/π, or another Brdf's f), for the statistical checks.
class Sampled final : public Brdf {
public:
    explicit Sampled(FactorSampler s, const Brdf* f = nullptr) : s_(std::move(s)), f_(f) {}
    int channels() const override { return 1; }
    std::size_t nbytes() const override { return s_.nbytes(); }
    std::string describe() const override { return "factor sampler"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override {
        return f_ ? f_->eval(wi, wo) : Rgb{M_1_PI, M_1_PI, M_1_PI};
    }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override { return s_.sample(wo, u1, u2); }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return s_.pdf(wo, wi); }

private:
    FactorSampler s_;
    const Brdf* f_;
};

// The factored BRDF sampled through its factor sampler (sample() itself uses its compact sampler).
Sampled by_factors(const Factored& f) { return Sampled(f.brdf->factor_sampler(), f.brdf.get()); }

}  // namespace

TEST_CASE("factor sampler: chi-square, normalisation, round trip on a synthetic factorisation", "[sample][factored][heavy]") {
    const Factored f = factor(coated({45, 45, 90}, 0.08), options(FactorMethod::Nmf, 3, FactorSpace::Linear,
                                                                  FactorLayout::HxDP, FactorColour::Separate));
    check_sampler(by_factors(f), 200000, test::kViewsLevel, kFactorChi2);
}

TEST_CASE("factor sampler: chi-square, normalisation, round trip over layouts, colours and spaces",
          "[sample][factored][heavy]") {
    const Table t = coated({45, 45, 90}, 0.08);
    const FactorOptions cases[] = {
        options(FactorMethod::Nmf, 3, FactorSpace::Linear, FactorLayout::HxDP, FactorColour::Separate),
        options(FactorMethod::Svd, 2, FactorSpace::Linear, FactorLayout::HDxP, FactorColour::Shared),
        options(FactorMethod::Nmf, 2, FactorSpace::Cos, FactorLayout::HxDP, FactorColour::Shared),
    };
    for (const FactorOptions& o : cases) {
        const Factored f = factor(t, o);
        INFO(label(f.brdf->factors()));
        check_sampler(by_factors(f), 1000000, test::kViewsLevel, kFactorChi2);
        // Lawrence's term mixture as the θh density.
        FactorSamplerOptions mixture;
        mixture.density = FactorDensity::Mixture;
        const FactorSampler s(f.brdf->factors(), mixture);
        check_sampler(Sampled(s, f.brdf.get()), 1000000, test::kViewsLevel, kFactorChi2);
    }
}

TEST_CASE("factor sampler: draws come from the factors' theta_h distribution", "[sample][factored]") {
    // Rank 1 whose u_0 is non-zero on rows 3..5 only: every data draw has θh in those rows' span (the
    // interpolation and the density, linear in s between row edges, reach rows 2..7 in bin coordinates), except the
    // floor's and the cosine share's draws.
    Factors f;
    f.grid = {16, 8, 16};
    f.method = FactorMethod::Nmf;
    f.space = FactorSpace::Linear;
    f.colour = FactorColour::Shared;
    f.u.assign(16, 0.0f);
    for (int r = 3; r <= 5; ++r) f.u[r] = 1.0f;
    f.v.assign(8 * 16, 0.5f);
    f.colour_weights = {1.0f, 1.0f, 1.0f};
    FactorSamplerOptions o;
    o.cosine_share = 0.05;
    o.floor = 1e-3;
    const FactorSampler s(f, o);
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(0, 1);
    const double lo = axis::u_to_theta_h(2.0, 16), hi = axis::u_to_theta_h(7.0, 16);
    for (double deg : {0.0, 45.0, 80.0}) {
        INFO("theta_o = " << deg);
        const Vec3 wo = spherical_direction(deg * M_PI / 180, 1.0);
        const int n = 100000;
        int outside = 0;
        for (int k = 0; k < n; ++k) {
            const BrdfSample d = s.sample(wo, u(rng), u(rng));
            REQUIRE(d.pdf > 0);
            const double theta_h = elevation(half_vector(d.wi, wo));
            outside += theta_h < lo || theta_h > hi;
        }
        // The cosine share (5%) and floor (0.1%) bound the draws outside; the factor's support takes the rest.
        CHECK(outside < 0.06 * n);
        CHECK(outside > 0.01 * n);  // the cosine share is really there
    }
    // And the density stays exact for factors with hard edges, with either θh density.
    check_sampler(Sampled(s), 150000, test::kViewsLevel, kFactorChi2);
    o.density = FactorDensity::Mixture;
    const FactorSampler mixture(f, o);
    check_sampler(Sampled(mixture), 100000, test::kViewsLevel, kFactorChi2);
}

TEST_CASE("factor sampler: random (wo, u) give finite, non-negative pdfs and weights, and no lost draws",
          "[sample][factored]") {
    const Factored f = factor(coated({32, 32, 64}, 0.03), options(FactorMethod::Svd, 2, FactorSpace::Linear,
                                                                  FactorLayout::HDxP, FactorColour::Shared));
    const RandomDraws r = random_draws(by_factors(f), 1000000, 5);
    CHECK(r.bad == 0);
    CHECK(r.failed < 10);  // the horizon truncation leaves only rounding at the horizon to fail
}

TEST_CASE("factor sampler: 10^7 random (wo, u)", "[sample][factored][heavy]") {
    const Factored f = factor(coated({32, 32, 64}, 0.02), options(FactorMethod::Nmf, 3, FactorSpace::Cos,
                                                                  FactorLayout::HxDP, FactorColour::Separate));
    const RandomDraws r = random_draws(by_factors(f), 10000000, 6);
    CHECK(r.bad == 0);
    CHECK(r.failed < 100);
}

TEST_CASE("factored: every space builds a factor sampler, sample() keeps the half-vector sampler", "[sample][factored]") {
    const Table t = coated({16, 16, 32}, 0.1);
    for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Cos, FactorSpace::Log, FactorSpace::Cbrt}) {
        const Factored f = factor(t, options(FactorMethod::Nmf, 2, space, FactorLayout::HxDP, FactorColour::Shared, 10));
        INFO(factor_space_name(space));
        const FactoredBrdf& b = *f.brdf;
        const Vec3 wo = spherical_direction(0.7, 0.2);
        const BrdfSample s = b.sample(wo, 0.3, 0.6), by_hv = b.sampler().sample(wo, 0.3, 0.6);
        REQUIRE(s.pdf > 0);
        CHECK(s.wi.x == by_hv.wi.x);
        CHECK(s.pdf == by_hv.pdf);
        CHECK(b.pdf(wo, s.wi) == b.sampler().pdf(wo, s.wi));
        const FactorSampler by_factors = b.factor_sampler();
        const BrdfSample d = by_factors.sample(wo, 0.3, 0.6);
        REQUIRE(d.pdf > 0);
        CHECK(d.pdf == Approx(by_factors.pdf(wo, d.wi)).epsilon(1e-9));
        CHECK(d.pdf != b.sampler().pdf(wo, d.wi));  // its own density, not the compact sampler's
    }
}

TEST_CASE("factor sampler: options out of range are rejected", "[sample][factored]") {
    const Factored f = factor(coated({8, 8, 16}, 0.1), options(FactorMethod::Nmf, 1, FactorSpace::Linear,
                                                               FactorLayout::HxDP, FactorColour::Shared, 5));
    const Factors& factors = f.brdf->factors();
    FactorSamplerOptions o;
    o.n_theta_o = 1;
    CHECK_THROWS_AS(FactorSampler(factors, o), ValueError);
    o = {};
    o.n_phi = 0;
    CHECK_THROWS_AS(FactorSampler(factors, o), ValueError);
    o = {};
    o.cosine_share = 0.0;
    CHECK_THROWS_AS(FactorSampler(factors, o), ValueError);
    o = {};
    o.floor = std::nan("");
    CHECK_THROWS_AS(FactorSampler(factors, o), ValueError);
    o = {};
    o.density = static_cast<FactorDensity>(7);
    CHECK_THROWS_AS(FactorSampler(factors, o), ValueError);
}

namespace {

// The real-data checks on one MERL table: a small linear nmf of it, sampled from its factors.
void check_merl(const std::filesystem::path& path, std::size_t samples) {
    INFO(path);
    const Loaded l = load(path.string());
    const auto* source = dynamic_cast<const TabularBrdf*>(l.brdf.get());
    REQUIRE(source);
    const Factored f = factor(source->table(), options(FactorMethod::Nmf, 2, FactorSpace::Linear, FactorLayout::HxDP,
                                                       FactorColour::Shared, 10));
    check_sampler(by_factors(f), samples, test::kViewsLevel, kFactorChi2);
    const RandomDraws r = random_draws(by_factors(f), 200000, 9);
    CHECK(r.bad == 0);
    CHECK(r.failed < 10);
}

}  // namespace

TEST_CASE("factor sampler on a real MERL table (chrome)", "[sample][factored][data][heavy]") {
    const auto files = test::merl_tables();
    const auto chrome = std::find_if(files.begin(), files.end(), [](const auto& p) { return p.stem() == "chrome"; });
    if (chrome == files.end()) {
        WARN("skipped: no MERL chrome table (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    check_merl(*chrome, 150000);
}

TEST_CASE("factor sampler on every real MERL table", "[sample][factored][data][heavy]") {
    const auto files = test::merl_tables();
    if (files.empty()) {
        WARN("skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    for (const auto& path : files) check_merl(path, 1000000);
}
