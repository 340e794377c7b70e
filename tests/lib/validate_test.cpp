#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/validate.h"

using namespace brdfz;

namespace {

constexpr double kPi = std::numbers::pi;

// f = c·(1 + a·cosθi) (depends on wi only, so non-reciprocal for a ≠ 0), or f = c where wi.x > 0.5 and
// `below` elsewhere (a negative below: negative values).
class Synthetic final : public Brdf {
public:
    Synthetic(double c, double a, double below = 0.0, bool split = false) : c_(c), a_(a), below_(below), split_(split) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "synthetic"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3&) const override {
        const double f = split_ && wi.x <= 0.5 ? below_ : c_ * (1.0 + a_ * wi.z);
        return {f, f, f};
    }

private:
    double c_, a_, below_;
    bool split_;
};

ValidateOptions small_grid() {
    ValidateOptions o;
    o.grid = GridSpec{12, 12, 24};
    return o;
}

}  // namespace

TEST_CASE("validate: a Lambertian passes every check, with the counts of what was tested", "[validate]") {
    const ValidationReport r = validate(Synthetic(0.6 / kPi, 0.0), small_grid());
    REQUIRE(r.checks.size() == 3);
    CHECK(r.ok());
    CHECK(r.failed_names().empty());
    CHECK(r.checks[0].name == "non-negativity");
    CHECK(r.checks[1].name == "reciprocity");
    CHECK(r.checks[1].tested == 17 * 17 * 16);
    CHECK(r.checks[2].name == "energy");
    CHECK(r.checks[2].tested == 10);
    // Bins of a 12x12x24 grid with both directions above the horizon: at most all, and most of them.
    CHECK(r.checks[0].tested <= 12 * 12 * 24);
    CHECK(r.checks[0].tested > 12 * 12 * 24 / 2);
    for (const ValidationCheck& c : r.checks) CHECK((c.failed == 0 && c.worst.empty()));
}

TEST_CASE("validate: energy reports the albedo viewed and the reflectance lit, which differ without reciprocity",
          "[validate]") {
    // f = c(1 + a cosθi): albedo viewed at θo ∫ f cosθi dωi = cπ(1 + 2a/3) at every θo; reflectance lit
    // from θi ∫ f cosθo dωo = cπ(1 + a cosθi).
    const double c = 1.0 / kPi, a = 0.5;
    ValidateOptions o = small_grid();
    o.theta_deg = {0.0, 60.0, 85.0};
    const ValidationReport r = validate(Synthetic(c, a), o);
    const ValidationCheck& e = r.checks[2];
    CHECK(!r.ok());
    CHECK(r.failed_names() == "reciprocity, energy");
    CHECK(e.failed == 3);
    REQUIRE(e.worst.size() == 3);
    CHECK(e.f_name == "albedo_viewed");
    CHECK(e.g_name == "reflectance_lit");
    // The worst first: lit at 0° is cπ(1 + a) = 1.5, the largest figure.
    CHECK(e.worst[0].theta_i_deg == 0.0);
    for (const ValidationOffence& w : e.worst) {
        CHECK(w.theta_i_deg == w.theta_o_deg);
        CHECK(w.f[0] == Approx(c * kPi * (1 + 2 * a / 3)).epsilon(1e-6));
        CHECK(w.g[1] == Approx(c * kPi * (1 + a * std::cos(w.theta_i_deg * kPi / 180))).epsilon(1e-6));
    }
    for (std::size_t k = 1; k < e.worst.size(); ++k) CHECK(e.worst[k - 1].badness >= e.worst[k].badness);
}

TEST_CASE("validate: reciprocity names the pairs whose swap differs most, up to the tolerance", "[validate]") {
    ValidateOptions o = small_grid();
    const ValidationReport r = validate(Synthetic(0.2 / kPi, 0.5), o);
    const ValidationCheck& rec = r.checks[1];
    CHECK(rec.failed > 0);
    REQUIRE(rec.worst.size() == o.worst);
    for (const ValidationOffence& w : rec.worst) {
        // f(wi, wo) and f(wo, wi) as reported: c(1 + a cosθi) and c(1 + a cosθo).
        CHECK(w.f[0] == Approx(0.2 / kPi * (1 + 0.5 * std::cos(w.theta_i_deg * kPi / 180))));
        CHECK(w.g[0] == Approx(0.2 / kPi * (1 + 0.5 * std::cos(w.theta_o_deg * kPi / 180))));
        // The most different elevations of the fixed set: 2.5° against 82.5°.
        CHECK(std::fabs(w.theta_i_deg - w.theta_o_deg) == Approx(80.0));
    }
    // Loose enough tolerances accept the same data.
    o.rtol = 1.0;
    CHECK(validate(Synthetic(0.2 / kPi, 0.5), o).checks[1].ok());
}

TEST_CASE("validate: non-negativity reads a table's stored values and evaluates other BRDFs", "[validate]") {
    ValidateOptions o = small_grid();
    const ValidationReport r = validate(Synthetic(0.1, 0.0, -0.25, true), o);
    const ValidationCheck& n = r.checks[0];
    CHECK(n.failed > 0);
    CHECK(n.failed < n.tested);
    REQUIRE(!n.worst.empty());
    CHECK(n.worst[0].f[0] == -0.25);
    CHECK(n.worst[0].badness == 0.25);
    CHECK(n.g_name.empty());

    // A table: its own grid, not options.grid, and only the bins that hold a value. Bin (1, 1, 3) lies
    // above the horizon at this grid's bin centres; one channel there is negative, another bin unmeasured.
    const GridSpec g{6, 6, 12};
    Table t(g);
    for (std::size_t bin = 0; bin < t.bins(); ++bin) t.set(bin, {0.1, 0.1, 0.1});
    t.set(g.index(1, 1, 3), {0.1, -1.0, 0.1});
    t.invalidate(g.index(2, 1, 3));
    const ValidationReport tr = validate(TabularBrdf(std::move(t)), o);
    ValidateOptions on_g = o;
    on_g.grid = g;
    CHECK(tr.checks[0].tested + 1 == validate(Synthetic(0.1, 0.0), on_g).checks[0].tested);
    CHECK(tr.checks[0].failed == 1);
    REQUIRE(tr.checks[0].worst.size() == 1);
    CHECK(tr.checks[0].worst[0].f[1] == -1.0);
}

TEST_CASE("validate: bad options are ValueErrors", "[validate]") {
    const Synthetic l(0.5 / kPi, 0.0);
    ValidateOptions o = small_grid();
    o.theta_deg = {};
    CHECK_THROWS_AS(validate(l, o), ValueError);
    o.theta_deg = {90.0};
    CHECK_THROWS_AS(validate(l, o), ValueError);
    o.theta_deg = {std::nan("")};
    CHECK_THROWS_AS(validate(l, o), ValueError);
    o = small_grid();
    o.rtol = -0.1;
    CHECK_THROWS_AS(validate(l, o), ValueError);
    o = small_grid();
    o.albedo_tol = std::nan("");
    CHECK_THROWS_AS(validate(l, o), ValueError);
    o = small_grid();
    o.grid.n_theta_h = 0;
    CHECK_THROWS_AS(validate(l, o), ValueError);
}
