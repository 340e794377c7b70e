// Error metrics (metrics.h): over the grid and over direction pairs uniform in solid angle.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/measurements.h"
#include "brdfz/metrics.h"
#include "brdfz/tabulate.h"

using namespace brdfz;

namespace {

// f = value everywhere above the horizon, measured up to `theta_max`.
class Constant final : public Brdf {
public:
    explicit Constant(double value, double theta_max = std::numbers::pi / 2) : value_(value), theta_max_(theta_max) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 8; }
    std::string describe() const override { return "constant"; }
    double measured_theta_max() const override { return theta_max_; }

protected:
    Rgb eval_above(const Vec3&, const Vec3&) const override { return {value_, value_, value_}; }

private:
    double value_, theta_max_;
};

// f = a + b·cosθi: not reciprocal unless b = 0.
class Incident final : public Brdf {
public:
    Incident(double a, double b) : a_(a), b_(b) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 16; }
    std::string describe() const override { return "incident"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3&) const override {
        const double f = a_ + b_ * wi.z;
        return {f, f, f};
    }

private:
    double a_, b_;
};

// The same BRDF with wi and wo exchanged.
class Swapped final : public Brdf {
public:
    explicit Swapped(const Brdf& b) : b_(b) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "swapped"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wo, wi); }

private:
    const Brdf& b_;
};

MetricOptions over_directions(std::size_t n = std::size_t{1} << 18) {
    MetricOptions o;
    o.over = Over::Directions;
    o.directions = n;
    return o;
}

// E[g(cosθ)] for θ uniform in solid angle over θ < θmax: cosθ is uniform on [cos θmax, 1].
template <typename G>
double cap_mean(double theta_max, G g) {
    const double c = std::cos(theta_max);
    const int n = 200000;
    double s = 0;
    for (int k = 0; k < n; ++k) s += g(c + (1.0 - c) * (k + 0.5) / n);
    return s / n;
}

}  // namespace

TEST_CASE("metrics over directions: known answers for two constant BRDFs", "[metrics]") {
    const double a = 0.3, b = 0.2;
    const Constant ref(a), app(b);
    const Metrics m = compare(ref, app, over_directions());
    REQUIRE(m.samples == (std::size_t{1} << 18));
    CHECK(m.negatives == 0);
    const double theta_max = 80.0 * std::numbers::pi / 180.0;
    // x = a·cosθi, y = b·cosθi with θi uniform in solid angle below 80°.
    const double cos_rmse = std::abs(a - b) * std::sqrt(cap_mean(theta_max, [](double z) { return z * z; }));
    CHECK(m.cos_rmse.mean == Approx(cos_rmse).epsilon(3e-3));
    // The ratio of sums does not depend on the distribution of θi.
    CHECK(m.cos_rmse_rel.mean == Approx(std::abs(a - b) / a).epsilon(1e-12));
    const double log_rmse = std::sqrt(cap_mean(theta_max, [&](double z) {
        const double d = std::log1p(a * z) - std::log1p(b * z);
        return d * d;
    }));
    CHECK(m.log_rmse.mean == Approx(log_rmse).epsilon(3e-3));
    const double cbrt_rmse = std::abs(std::cbrt(a) - std::cbrt(b)) *
                             std::sqrt(cap_mean(theta_max, [](double z) { return std::cbrt(z) * std::cbrt(z); }));
    CHECK(m.cbrt_rmse.mean == Approx(cbrt_rmse).epsilon(3e-3));
    // Over the grid the same BRDFs give a different cos_rmse: each bin counts once, not its solid angle.
    const Metrics g = compare(ref, app);
    CHECK(g.cos_rmse_rel.mean == Approx(std::abs(a - b) / a).epsilon(1e-9));
    CHECK(std::abs(g.cos_rmse.mean - cos_rmse) > 0.01 * cos_rmse);
}

TEST_CASE("metrics over directions: pairs uniform in solid angle within the cut-offs", "[metrics]") {
    // A reference measured up to 40°: wi stays below 40°, wo goes up to max_theta_deg (80°).
    const double measured = 40.0 * std::numbers::pi / 180.0;
    const Constant ref(0.5, measured);
    const MetricSamples s = metric_samples(ref, over_directions(1 << 16));
    REQUIRE(s.wi.size() == (1u << 16));
    REQUIRE(s.wo.size() == s.wi.size());
    REQUIRE(s.reference.size() == s.wi.size());
    const double ci = std::cos(measured), co = std::cos(80.0 * std::numbers::pi / 180.0);
    double zi = 0, zo = 0, xi = 0, yo = 0, zo_min = 1;
    for (std::size_t k = 0; k < s.wi.size(); ++k) {
        REQUIRE(s.wi[k].z > ci);
        REQUIRE(s.wo[k].z > co);
        REQUIRE(length(s.wi[k]) == Approx(1.0).epsilon(1e-12));
        REQUIRE(s.reference[k][0] == 0.5);
        zi += s.wi[k].z, zo += s.wo[k].z, xi += s.wi[k].x, yo += s.wo[k].y;
        zo_min = std::min(zo_min, s.wo[k].z);
    }
    const double n = static_cast<double>(s.wi.size());
    // cosθ uniform on [cos θmax, 1]: mean (1 + cos θmax)/2 (standard error ~1e-3 here); azimuths uniform.
    CHECK(zi / n == Approx((1.0 + ci) / 2).margin(4e-3));
    CHECK(zo / n == Approx((1.0 + co) / 2).margin(4e-3));
    CHECK(std::abs(xi / n) < 4e-3);
    CHECK(std::abs(yo / n) < 4e-3);
    CHECK(zo_min < std::cos(79.0 * std::numbers::pi / 180.0));
    // The pairs are a function of (index, seed) only.
    std::vector<Vec3> wi(100), wo(100);
    direction_pairs(1000, MetricOptions{}.seed, measured, 80.0 * std::numbers::pi / 180.0, wi, wo);
    CHECK(wi[5].x == s.wi[1005].x);
    CHECK(wo[99].z == s.wo[1099].z);
    MetricOptions other = over_directions(1 << 16);
    other.seed = 2;
    CHECK(metric_samples(ref, other).wi[0].x != s.wi[0].x);
}

TEST_CASE("metrics: the samples and compare_values reproduce compare", "[metrics]") {
    const Incident ref(0.2, 0.5), app(0.25, 0.3);
    for (Over over : {Over::Grid, Over::Directions}) {
        MetricOptions o = over == Over::Grid ? MetricOptions{} : over_directions(50000);
        o.threads = 1;
        const Metrics m = compare(ref, app, o);
        const MetricSamples s = metric_samples(ref, o);
        std::vector<Rgb> f(s.wi.size());
        app.eval(s.wi, s.wo, f);
        const Metrics v = compare_values(s.wi, s.reference, f);
        CHECK(v.samples == m.samples);
        CHECK(v.cos_rmse.mean == Approx(m.cos_rmse.mean).epsilon(1e-12));
        CHECK(v.cos_rmse_rel.mean == Approx(m.cos_rmse_rel.mean).epsilon(1e-12));
        CHECK(v.log_rmse.mean == Approx(m.log_rmse.mean).epsilon(1e-12));
        CHECK(v.cbrt_rmse.mean == Approx(m.cbrt_rmse.mean).epsilon(1e-12));
        // Not a function of the thread count.
        o.threads = 2;
        CHECK(compare(ref, app, o).cos_rmse.r == m.cos_rmse.r);
    }
}

TEST_CASE("metrics over directions tell a BRDF from itself with wi and wo exchanged", "[metrics]") {
    const Incident src(0.1, 0.4);
    const Swapped swapped(src);
    const Metrics self = compare(src, src, over_directions(1 << 14));
    CHECK(self.cos_rmse.mean == 0.0);
    const Metrics sw = compare(src, swapped, over_directions(1 << 14));
    CHECK(sw.cos_rmse_rel.mean > 0.2);
}

TEST_CASE("metrics over directions: bad options and measurements", "[metrics]") {
    const Constant ref(0.3);
    CHECK_THROWS_AS(compare(ref, ref, over_directions(0)), ValueError);
    CHECK_THROWS_AS(compare(ref, ref, over_directions(MetricOptions::kMaxDirections + 1)), ValueError);
    MetricOptions o = over_directions(16);
    o.max_theta_deg = 0.0;
    CHECK_THROWS_AS(compare(ref, ref, o), ValueError);
    CHECK_THROWS_AS(compare(Constant(0.3, 0.0), ref, over_directions(16)), ValueError);
    MeasurementSet set;
    set.samples.push_back({{0, 0, 1}, {0, 0, 1}, {0.1, 0.1, 0.1}});
    CHECK_THROWS_WITH(compare(set, ref, over_directions(16)), Catch::Contains("need a BRDF as the reference"));
    CHECK(compare(set, ref).samples == 1);
    CHECK_THROWS_AS(parse_over("grids"), ValueError);
    CHECK(parse_over(over_name(Over::Directions)) == Over::Directions);
    const std::vector<Vec3> wi(2, Vec3{0, 0, 1});
    const std::vector<Rgb> f(3);
    CHECK_THROWS_AS(compare_values(wi, f, f), ValueError);
}
