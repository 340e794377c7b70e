#include <catch2/catch.hpp>

#include <cmath>

#include "brdfz/albedo.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"

using namespace brdfz;

namespace {

// f = ρ/π per channel, or a fixed value (possibly negative or NaN) to test the policies.
class Constant final : public Brdf {
public:
    explicit Constant(Rgb f) : f_(f) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return sizeof f_; }
    std::string describe() const override { return "constant"; }

protected:
    Rgb eval_above(const Vec3&, const Vec3&) const override { return f_; }

private:
    Rgb f_;
};

Constant lambert(Rgb rho) { return Constant({rho[0] / M_PI, rho[1] / M_PI, rho[2] / M_PI}); }

}  // namespace

TEST_CASE("directional albedo of a Lambertian is its reflectance", "[albedo]") {
    const Rgb rho{0.2, 0.5, 0.9};
    const Constant l = lambert(rho);
    for (double deg : {0.0, 30.0, 60.0, 80.0, 89.0}) {
        const Rgb a = directional_albedo(l, deg * M_PI / 180);
        for (int c = 0; c < 3; ++c) CHECK(a[c] == Approx(rho[c]).epsilon(1e-6));
    }
    CHECK_THROWS(directional_albedo(l, M_PI / 2));
    CHECK_THROWS(directional_albedo(l, std::nan("")));
}

TEST_CASE("a tabulated Lambertian keeps its albedo within 1e-3", "[tabulate][albedo]") {
    const Rgb rho{0.2, 0.5, 0.9};
    const Tabulated t = tabulate(lambert(rho));
    CHECK(t.counts.valid + t.counts.below_horizon == t.table.bins());
    CHECK(t.counts.below_horizon > 0);
    for (Lookup lookup : {Lookup::Linear, Lookup::Nearest}) {
        const TabularBrdf table(t.table, lookup);
        for (double deg : {0.0, 30.0, 60.0, 80.0}) {
            const Rgb a = directional_albedo(table, deg * M_PI / 180);
            for (int c = 0; c < 3; ++c) CHECK(a[c] == Approx(rho[c]).margin(1e-3));
        }
    }
}

TEST_CASE("tabulation marks below-horizon bins invalid and applies the negative policy", "[tabulate]") {
    TabulateOptions o;
    o.grid = GridSpec{16, 16, 32};
    const Tabulated clamp = tabulate(Constant({-1.0, 0.5, 0.5}), o);
    CHECK(clamp.counts.clamped == clamp.counts.valid);
    CHECK(clamp.counts.negative == 0);
    o.negative = NegativePolicy::Invalidate;
    const Tabulated inval = tabulate(Constant({-1.0, 0.5, 0.5}), o);
    CHECK(inval.counts.valid == 0);
    CHECK(inval.counts.negative == clamp.counts.valid);
    const Tabulated nan = tabulate(Constant({0.1, std::nan(""), 0.5}), o);
    CHECK(nan.counts.valid == 0);
    CHECK(nan.counts.nan == clamp.counts.valid);
    const Tabulated inf = tabulate(Constant({0.1, 1e300, 0.5}), o);
    CHECK(inf.counts.inf == clamp.counts.valid);

    // A bin is invalid exactly when its sample pair is below the horizon.
    const GridSpec& g = clamp.table.grid();
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id) {
            const auto [wi, wo] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(0)});
            CHECK(clamp.table.valid(g.index(ih, id, 0)) == (wi.z > 0 && wo.z > 0));
        }
}

TEST_CASE("tabulation is identical for any thread count and reports progress", "[tabulate]") {
    const CoatedDiffuse m;
    TabulateOptions o;
    o.grid = GridSpec{30, 30, 60};
    o.threads = 1;
    double last = 0;
    o.progress = [&](double f) { last = f; };
    const Tabulated one = tabulate(m, o);
    CHECK(last == 1.0);
    o.threads = 3;
    o.progress = nullptr;
    CHECK(tabulate(m, o).table == one.table);
}

TEST_CASE("metrics: zero against itself, known values against a scaled copy", "[metrics]") {
    const CoatedDiffuse m;
    TabulateOptions o;
    o.grid = GridSpec{45, 45, 90};
    const Tabulated t = tabulate(m, o);
    const TabularBrdf table(t.table);
    // At its own bin centres a table's nearest lookup is exact, its linear lookup nearly so.
    const Metrics self = compare(table, TabularBrdf(t.table, Lookup::Nearest));
    CHECK(self.cos_rmse.mean == 0.0);
    CHECK(self.log_rmse.mean == 0.0);
    CHECK(self.cbrt_rmse.mean == 0.0);
    CHECK(self.samples > 0);
    CHECK(compare(table, table).cos_rmse_rel.mean < 1e-7);

    Table scaled = t.table;
    for (std::size_t k = 0; k < 3 * scaled.bins(); ++k) scaled.data()[k] *= 1.1f;
    const Metrics s = compare(table, TabularBrdf(scaled));
    for (double v : {s.cos_rmse_rel.r, s.cos_rmse_rel.g, s.cos_rmse_rel.b}) CHECK(v == Approx(0.1).epsilon(1e-5));
    CHECK(s.cos_rmse.mean > 0.0);
    CHECK(s.log_rmse.mean > 0.0);
    CHECK(s.cbrt_rmse.mean > 0.0);
    CHECK(s.cos_rmse.mean == Approx((s.cos_rmse.r + s.cos_rmse.g + s.cos_rmse.b) / 3));

    // Negative reference values (measurement noise) are taken as 0 and counted: the non-negative
    // copy of a table with negatives matches it exactly.
    Table noisy = t.table, clamped = t.table;
    for (std::size_t bin = 0; bin < noisy.bins(); bin += 7) {
        noisy.data()[3 * bin + 2] = -0.5f;
        clamped.data()[3 * bin + 2] = 0.0f;
    }
    const Metrics n = compare(TabularBrdf(noisy, Lookup::Nearest), TabularBrdf(clamped, Lookup::Nearest));
    CHECK(n.cos_rmse.mean == 0.0);
    CHECK(n.cos_rmse_rel.mean == 0.0);
    CHECK(n.log_rmse.mean == 0.0);
    CHECK(n.cbrt_rmse.mean == 0.0);
    CHECK(n.negatives > 0);
    CHECK(n.negatives == compare(TabularBrdf(noisy, Lookup::Nearest), TabularBrdf(noisy, Lookup::Nearest)).negatives / 2);

    // Only bins with θi, θo under the cut-off count.
    MetricOptions narrow;
    narrow.max_theta_deg = 40;
    CHECK(compare(table, table, narrow).samples < self.samples);
    // Analytic reference: sampled between the table's bin centres, the table is close but not exact.
    const Metrics between = compare(m, table);
    CHECK(between.cos_rmse_rel.mean > 1e-4);
    CHECK(between.cos_rmse_rel.mean < 0.05);
}

TEST_CASE("least-squares tabulation fits the linear lookup better than point or box samples", "[tabulate]") {
    const CoatedDiffuse m;  // a glossy coat: under-resolved by a coarse grid
    TabulateOptions o;
    o.grid = GridSpec{12, 8, 8};
    const Tabulated point = tabulate(m, o);
    o.supersample = {3, 3, 3};
    const Tabulated box = tabulate(m, o);
    o.filter = TabulateOptions::Filter::LeastSquares;
    const Tabulated lsq = tabulate(m, o);
    // The same bins valid; values finite and >= 0.
    CHECK(lsq.counts.valid == point.counts.valid);
    for (std::size_t bin = 0; bin < lsq.table.bins(); ++bin) {
        CHECK(lsq.table.valid(bin) == point.table.valid(bin));
        for (int c = 0; c < 3; ++c)
            if (lsq.table.valid(bin)) CHECK(lsq.table.at(bin, c) >= 0.0f);
    }
    // It minimises the cosine-weighted error at the points it was fitted to, so it is below point and
    // box samples there, and (the point of it) between them: on the metric's own grid.
    MetricOptions fitted;
    fitted.grid = GridSpec{36, 24, 24, BinPosition::Centre};
    const double e_lsq = compare(m, TabularBrdf(lsq.table), fitted).cos_rmse_rel.mean;
    CHECK(e_lsq < compare(m, TabularBrdf(point.table), fitted).cos_rmse_rel.mean);
    CHECK(e_lsq < compare(m, TabularBrdf(box.table), fitted).cos_rmse_rel.mean);
    const double g_lsq = compare(m, TabularBrdf(lsq.table)).cos_rmse_rel.mean;
    CHECK(g_lsq < compare(m, TabularBrdf(point.table)).cos_rmse_rel.mean);
    CHECK(g_lsq < compare(m, TabularBrdf(box.table)).cos_rmse_rel.mean);

    // A constant is reproduced exactly; negative results would be clamped and counted.
    const Rgb rho{0.2, 0.5, 0.9};
    const Tabulated flat = tabulate(lambert(rho), o);
    CHECK(flat.counts.clamped == 0);
    for (std::size_t bin = 0; bin < flat.table.bins(); ++bin)
        if (flat.table.valid(bin))
            for (int c = 0; c < 3; ++c) CHECK(flat.table.at(bin, c) == Approx(rho[c] / M_PI).epsilon(1e-6));

    o.supersample = {64, 64, 64};
    CHECK_THROWS_AS(tabulate(m, o), ValueError);
}

TEST_CASE("least squares and box filters on a warped θd axis", "[tabulate][warp]") {
    const CoatedDiffuse m;
    TabulateOptions o;
    o.grid = GridSpec{12, 8, 8, BinPosition::Centre, 0.8};
    const Tabulated point = tabulate(m, o);
    o.supersample = {3, 3, 3};
    const Tabulated box = tabulate(m, o);
    o.filter = TabulateOptions::Filter::LeastSquares;
    const Tabulated lsq = tabulate(m, o);
    CHECK(lsq.table.grid() == o.grid);
    CHECK(lsq.counts.valid == point.counts.valid);
    // Its points are weighted back to the metric's uniform θd, so it still beats point and box samples
    // on a metric grid (half the default resolution per axis: cheaper, same weighting).
    MetricOptions judge;
    judge.grid = GridSpec{45, 45, 90, BinPosition::Start};
    const double e_lsq = compare(m, TabularBrdf(lsq.table), judge).cos_rmse_rel.mean;
    CHECK(e_lsq < compare(m, TabularBrdf(point.table), judge).cos_rmse_rel.mean);
    CHECK(e_lsq < compare(m, TabularBrdf(box.table), judge).cos_rmse_rel.mean);
    // A constant is reproduced exactly by both filters.
    const Rgb rho{0.2, 0.5, 0.9};
    for (auto filter : {TabulateOptions::Filter::Box, TabulateOptions::Filter::LeastSquares}) {
        o.filter = filter;
        const Tabulated flat = tabulate(lambert(rho), o);
        for (std::size_t bin = 0; bin < flat.table.bins(); ++bin)
            if (flat.table.valid(bin))
                for (int c = 0; c < 3; ++c) CHECK(flat.table.at(bin, c) == Approx(rho[c] / M_PI).epsilon(1e-6));
    }
}
