#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "brdfz/repr/analytic/catalogue.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/runtime/kernels/lobe_mixture.h"
#include "brdfz/sample/lobes.h"
#include "sample_stats.h"

using namespace brdfz;
namespace rk = brdfz::runtime::kernels;

// The runtime's constants are std::numbers' (the lobes' bits depend on it).
static_assert(lobes::kPi == std::numbers::pi);
static_assert(lobes::kInvPi == std::numbers::inv_pi);

TEST_CASE("the runtime's lobe families are the catalogue's, id for id", "[runtime][analytic]") {
    REQUIRE(rk::kLobeFamilies.size() == lobe_types().size());
    for (std::size_t i = 0; i < rk::kLobeFamilies.size(); ++i) {
        const rk::LobeFamily& f = rk::kLobeFamilies[i];
        const LobeType& t = lobe_types()[i];
        INFO(t.name);
        CHECK(f.name == t.name);
        CHECK(f.params == t.params.size());
        CHECK(f.eval == t.eval);
        CHECK(f.sample == lobe_sampler(t).sample);
        CHECK(f.pdf == lobe_sampler(t).pdf);
        CHECK(rk::lobe_family(t.name) == static_cast<int>(i));
        CHECK(find_lobe_type(t.name) == static_cast<int>(i));
    }
    CHECK(rk::lobe_family("ggx2") == -1);  // a repeat count is the model string's, not a name
    CHECK(rk::lobe_family("phong") == -1);
    CHECK(rk::lobe_family("") == -1);
}

namespace {

// A model as an exported material holds it: family ids from the terms' names, offsets, parameters and
// the sampler's albedo table, copied out of the library's objects.
struct Exported {
    std::vector<rk::LobeTerm> terms;
    std::vector<double> params, albedo;
    explicit Exported(const AnalyticBrdf& b)
        : params(b.params().begin(), b.params().end()), albedo(b.sampler().albedo_table()) {
        for (const Model::Term& t : b.model().terms()) terms.push_back({rk::lobe_family(t.type->name), t.offset});
    }
    rk::LobeMixtureView view() const { return {terms.data(), terms.size(), params.data(), albedo.data()}; }
};

std::vector<double> random_params(const Model& m, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> p(m.size());
    for (std::size_t i = 0; i < m.size(); ++i) {
        const ParamSpec& s = m.spec(i);
        p[i] = s.kind == ParamKind::LogScale ? s.lo * std::pow(s.hi / s.lo, u(rng)) : s.lo + (s.hi - s.lo) * u(rng);
    }
    return p;
}

// Views above the horizon, a tenth of them grazing (cosθo below 1e-3), and the normal view.
Vec3 random_view(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double z = u(rng) < 0.1 ? 1e-3 * (1.0 - u(rng)) : 1.0 - u(rng);
    const double s = std::sqrt(1.0 - z * z), phi = 2.0 * std::numbers::pi * u(rng);
    return u(rng) < 0.01 ? Vec3{0.0, 0.0, 1.0} : Vec3{s * std::cos(phi), s * std::sin(phi), z};
}

double relative(double a, double b) { return a == b ? 0.0 : std::fabs(a - b) / std::fmax(std::fabs(a), std::fabs(b)); }

// n draws of the runtime kernel against the library's batch kernel (LobeMixture::sample_block), its
// batch eval and the mixture's density written out with the catalogue's samplers: the same wi and pdf
// to the bit, eval and the density at random pairs to 1e-12.
void check_agreement(const AnalyticBrdf& b, std::size_t n, std::mt19937_64& rng) {
    INFO(b.describe());
    const Exported e(b);
    const rk::LobeMixtureView v = e.view();
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3> wo(n), other(n), drawn(n);
    std::vector<std::array<double, 2>> us(n);
    for (std::size_t k = 0; k < n; ++k) {
        wo[k] = random_view(rng);
        other[k] = random_view(rng);
        us[k] = {u(rng), u(rng)};
    }
    std::vector<BrdfSample> block(n);
    b.sampler().sample_block(wo.data(), us.data(), n, block.data());
    std::size_t failed = 0, mismatched = 0, off = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const rk::LobeMixtureDraw d = rk::lobe_mixture_sample(v, wo[k], us[k][0], us[k][1]);
        const BrdfSample& s = block[k];
        const bool same = test::same_bits(d.pdf, s.pdf) && test::same_bits(d.wi.x, s.wi.x) &&
                          test::same_bits(d.wi.y, s.wi.y) && test::same_bits(d.wi.z, s.wi.z);
        mismatched += !same;
        if (d.pdf == 0.0) {
            ++failed;
            drawn[k] = other[k];
            continue;
        }
        drawn[k] = d.wi;
        // sample's pdf is pdf() at the drawn direction, to the bit.
        off += !test::same_bits(rk::lobe_mixture_pdf(v, wo[k], d.wi), d.pdf);
    }
    CHECK(mismatched == 0);
    CHECK(off == 0);
    CHECK(failed < n / 100);

    // eval against the library's batch eval (its own vectorised kernel), at the drawn and at random pairs.
    for (const std::vector<Vec3>* wi : {&drawn, &other}) {
        std::vector<Rgb> f(n);
        b.eval(*wi, wo, f);
        double worst = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
            double r[3];
            rk::lobe_mixture_eval(v, (*wi)[k], wo[k], r);
            for (int c = 0; c < 3; ++c) worst = std::fmax(worst, relative(r[c], f[k][c]));
        }
        CHECK(worst <= 1e-12);
    }

    // The density at random pairs against the mixture written out: the lobe weights from the table,
    // each family's pdf folded onto the upper hemisphere; the cosine density where the model is black.
    double worst = 0.0;
    std::size_t weights_differ = 0, unnormalised = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const Vec3& i = other[k];
        double w[rk::kMaxLobeTerms];
        const bool lit = rk::lobe_mixture_weights(v, wo[k], w);
        const std::vector<double> core = b.sampler().weights(wo[k]);
        double expect = lit ? 0.0 : i.z / std::numbers::pi, total = 0.0;
        for (std::size_t j = 0; j < e.terms.size(); ++j) {
            weights_differ += !test::same_bits(w[j], core[j]);
            const Model::Term& t = b.model().terms()[j];
            const LobeSampler& s = lobe_sampler(*t.type);
            const double* p = e.params.data() + t.offset;
            if (w[j] > 0.0) expect += w[j] * (s.pdf(p, wo[k], i) + s.pdf(p, wo[k], {i.x, i.y, -i.z}));
            total += w[j];
        }
        unnormalised += lit ? !(std::fabs(total - 1.0) < 1e-12) : total != 0.0;
        worst = std::fmax(worst, relative(rk::lobe_mixture_pdf(v, wo[k], i), expect));
        worst = std::fmax(worst, relative(b.pdf(wo[k], i), expect));
    }
    CHECK(weights_differ == 0);
    CHECK(unnormalised == 0);
    CHECK(worst <= 1e-12);
}

}  // namespace

TEST_CASE("the runtime's lobe mixture agrees with the library on every family: 10^5 draws each",
          "[runtime][analytic]") {
    std::mt19937_64 rng(2024);
    for (const LobeType& t : lobe_types()) {
        const Model m = Model::parse(t.name);
        // The defaults, then random parameters: 10^5 (wo, u) in all.
        check_agreement(AnalyticBrdf(m, m.defaults()), 20000, rng);
        for (int i = 0; i < 4; ++i) check_agreement(AnalyticBrdf(m, random_params(m, rng)), 20000, rng);
    }
}

TEST_CASE("the runtime's lobe mixture agrees with the library on mixtures and black models: 10^5 draws each",
          "[runtime][analytic]") {
    std::mt19937_64 rng(2025);
    for (const char* model : {"lambert+ggx", "lambert+beckmann+ward", "lafortune3", "ggx_aniso+ashikhmin_shirley",
                              "lambert+ggx_conductor+blinn_phong+ggx_sep"}) {
        const Model m = Model::parse(model);
        check_agreement(AnalyticBrdf(m, m.defaults()), 50000, rng);
        check_agreement(AnalyticBrdf(m, random_params(m, rng)), 50000, rng);
    }
    // Black everywhere: every albedo 0, so the cosine density.
    const AnalyticBrdf black("lambert+ggx", {0, 0, 0, 0, 0, 0, 0.2, 0.04});
    check_agreement(black, 1000, rng);
}
