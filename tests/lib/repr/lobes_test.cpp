#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/errors.h"
#include "brdfz/repr/analytic/catalogue.h"
#include "brdfz/repr/analytic/model.h"

using namespace brdfz;

namespace {

Vec3 random_upper(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    Vec3 v = normalize({n(rng), n(rng), n(rng)});
    v.z = std::fabs(v.z);
    return v;
}

// Parameter vectors covering every corner of a lobe's bounds. Parameters named *_r, *_g, *_b act on
// their channel only, so one vector can put each channel at a different corner of its own parameters:
// the per-channel corners are spread over the channels, the shared parameters enumerated.
std::vector<std::vector<double>> corners(const LobeType& t) {
    const std::size_t n = t.params.size();
    std::vector<std::size_t> shared;
    std::vector<std::array<std::size_t, 3>> per_channel;  // indices of (x_r, x_g, x_b)
    for (std::size_t i = 0; i < n; ++i) {
        const std::string_view name = t.params[i].name;
        if (name.ends_with("_r")) per_channel.push_back({i, i + 1, i + 2});
        if (!name.ends_with("_r") && !name.ends_with("_g") && !name.ends_with("_b")) shared.push_back(i);
    }
    const std::size_t patterns = std::size_t{1} << per_channel.size();
    std::vector<std::vector<double>> out;
    for (std::size_t config = 0; config < (patterns + 2) / 3; ++config)
        for (std::size_t mask = 0; mask < (std::size_t{1} << shared.size()); ++mask) {
            std::vector<double> p(n);
            for (std::size_t j = 0; j < shared.size(); ++j) {
                const ParamSpec& s = t.params[shared[j]];
                p[shared[j]] = (mask >> j) & 1 ? s.hi : s.lo;
            }
            for (std::size_t c = 0; c < 3; ++c) {
                const std::size_t pattern = (3 * config + c) % patterns;
                for (std::size_t g = 0; g < per_channel.size(); ++g) {
                    const ParamSpec& s = t.params[per_channel[g][c]];
                    p[per_channel[g][c]] = (pattern >> g) & 1 ? s.hi : s.lo;
                }
            }
            out.push_back(p);
        }
    return out;
}

std::vector<double> random_params(const Model& m, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> p(m.size());
    for (std::size_t i = 0; i < m.size(); ++i) {
        const ParamSpec& s = m.spec(i);
        p[i] = s.kind == ParamKind::LogScale ? s.lo * std::pow(s.hi / s.lo, u(rng)) : s.lo + (s.hi - s.lo) * u(rng);
    }
    return p;
}

}  // namespace

namespace {

// The albedo of every lobe at every corner of its bounds, at every view elevation (`all_views`) or at
// one per corner, the corners taking the elevations in turn.
void check_corner_albedos(bool all_views) {
    const double views[] = {0.0, 30.0, 60.0, 80.0, 89.0};
    std::size_t next = 0;
    for (const LobeType& t : lobe_types()) {
        for (const std::vector<double>& p : corners(t)) {
            const AnalyticBrdf brdf(std::string(t.name), p);
            for (std::size_t v = 0; v < std::size(views); ++v) {
                if (!all_views && v != next % std::size(views)) continue;
                const double deg = views[v];
                // Four times the default panels: Beckmann at alpha = 0.001 is narrower than they resolve.
                const Rgb rho = directional_albedo(brdf, deg * M_PI / 180.0, {256, 64, 8});
                for (double c : rho) {
                    INFO(brdf.describe() << " at theta_o " << deg);
                    CHECK(c >= 0.0);
                    CHECK(c <= 1.0 + 1e-4);  // quadrature error of the albedo integral
                }
            }
            ++next;
        }
    }
}

}  // namespace

// The test below evaluates the same corners, one view elevation each.
TEST_CASE("every lobe conserves energy at the corners of its parameter bounds", "[lobes][albedo][heavy]") {
    check_corner_albedos(true);
}

TEST_CASE("every lobe conserves energy at the corners of its parameter bounds, one view each", "[lobes][albedo][light]") {
    check_corner_albedos(false);
}

TEST_CASE("lobes are reciprocal, non-negative and finite, grazing included", "[lobes]") {
    std::mt19937_64 rng(17);
    for (const LobeType& t : lobe_types()) {
        const Model m = Model::parse(t.name);
        for (int trial = 0; trial < 20; ++trial) {
            const AnalyticBrdf brdf(m, random_params(m, rng));
            for (int k = 0; k < 200; ++k) {
                const Vec3 wi = random_upper(rng), wo = random_upper(rng);
                const Rgb a = brdf.eval(wi, wo), b = brdf.eval(wo, wi);
                for (int c = 0; c < 3; ++c) {
                    INFO(brdf.describe());
                    REQUIRE(std::isfinite(a[c]));
                    CHECK(a[c] >= 0.0);
                    CHECK(a[c] == Approx(b[c]).epsilon(1e-10).margin(1e-300));
                }
            }
        }
        // Grazing and degenerate pairs at every corner: finite, and 0 below the horizon.
        const double tiny = 1e-300;
        const Vec3 pairs[][2] = {{{1, 0, tiny}, {-1, 0, tiny}},
                                 {{1, 0, tiny}, {1, 0, tiny}},
                                 {{0, 0, 1}, {0, 0, 1}},
                                 {{1, 0, 1e-8}, {0, 1, 1e-8}},
                                 {normalize({1, 0, 1e-150}), {0, 0, 1}}};
        for (const std::vector<double>& p : corners(t)) {
            const AnalyticBrdf brdf(std::string(t.name), p);
            for (const auto& pair : pairs) {
                const Rgb f = brdf.eval(pair[0], pair[1]);
                INFO(brdf.describe() << " at wi (" << pair[0].x << ", " << pair[0].y << ", " << pair[0].z << ")");
                for (double c : f) CHECK(std::isfinite(c));
            }
            CHECK(brdf.eval(Vec3{0, 0, -1}, Vec3{0, 0, 1}) == Rgb{0, 0, 0});
            CHECK(brdf.eval(Vec3{NAN, 0, 1}, Vec3{0, 0, 1}) == Rgb{0, 0, 0});
        }
    }
}

TEST_CASE("batch evaluation equals one-pair evaluation", "[lobes]") {
    std::mt19937_64 rng(5);
    const AnalyticBrdf brdf("lambert+ggx+beckmann_conductor+ward+lafortune2+ashikhmin_shirley+ggx_aniso+blinn_phong",
                            Model::parse("lambert+ggx+beckmann_conductor+ward+lafortune2+ashikhmin_shirley+ggx_aniso+blinn_phong").defaults());
    std::vector<Vec3> wi(1000), wo(1000);
    for (std::size_t k = 0; k < wi.size(); ++k) {
        wi[k] = random_upper(rng);
        wo[k] = random_upper(rng);
    }
    wi[3].z = -wi[3].z;        // below the horizon
    wo[7] = {NAN, 0.0, 1.0};   // non-finite
    std::vector<Rgb> f(wi.size());
    brdf.eval(wi, wo, f);
    for (std::size_t k = 0; k < wi.size(); ++k) {
        const Rgb one = brdf.eval(wi[k], wo[k]);
        for (int c = 0; c < 3; ++c) CHECK(f[k][c] == Approx(one[c]).epsilon(1e-14));
    }
    CHECK(f[3] == Rgb{0, 0, 0});
    CHECK(f[7] == Rgb{0, 0, 0});
}

namespace {

// Every family's template instantiated for float, against double, at its default parameters.
template <typename F>
void check_float(std::mt19937_64& rng) {
    std::array<double, F::params.size()> pd;
    std::array<float, F::params.size()> pf;
    for (std::size_t j = 0; j < pd.size(); ++j) pf[j] = static_cast<float>(pd[j] = F::params[j].init);
    for (int k = 0; k < 1000; ++k) {
        const Vec3 a = random_upper(rng), b = random_upper(rng);
        if (a.z < 0.05 || b.z < 0.05) continue;  // float cosines lose their relative precision at grazing
        const auto gd = make_geometry(a.x, a.y, a.z, b.x, b.y, b.z);
        const auto gf = make_geometry<float>(a.x, a.y, a.z, b.x, b.y, b.z);
        double vd[3];
        float vf[3];
        F::eval(gd, pd.data(), vd);
        F::eval(gf, pf.data(), vf);
        for (int c = 0; c < 3; ++c) {
            INFO(F::name << " channel " << c);
            CHECK(vf[c] == Approx(vd[c]).epsilon(1e-3).margin(1e-6 * (1.0 + std::fabs(vd[c]))));
        }
    }
}

template <typename... F>
void check_float_all(LobeList<F...>) {
    std::mt19937_64 rng(8);
    (check_float<F>(rng), ...);
}

}  // namespace

TEST_CASE("every lobe evaluates in float as in double", "[lobes]") { check_float_all(AllLobes{}); }

TEST_CASE("the microfacet lobe matches the closed form, and its pieces the existing helpers", "[lobes]") {
    // f = ks F D G2 / (4 cos_i cos_o) written out with microfacet.h's original GGX functions.
    std::mt19937_64 rng(3);
    for (int k = 0; k < 1000; ++k) {
        const Vec3 wi = random_upper(rng), wo = random_upper(rng);
        const double alpha = 0.3, eta = 1.6;
        const AnalyticBrdf brdf("ggx_dielectric", {0.9, 0.8, 0.7, alpha, eta});
        const Vec3 h = normalize(wi + wo);
        const double expect = microfacet::fresnel_dielectric(dot(wi, h), eta) * microfacet::ggx_d(h.z, alpha) *
                              microfacet::ggx_g2(wi.z, wo.z, alpha) / (4 * wi.z * wo.z);
        const Rgb f = brdf.eval(wi, wo);
        CHECK(f[0] == Approx(0.9 * expect).epsilon(1e-9));
        CHECK(f[2] == Approx(0.7 * expect).epsilon(1e-9));
    }
    // The exact conductor Fresnel: k = 0 is a dielectric; normal incidence ((n−1)² + k²) / ((n+1)² + k²).
    for (double c : {1.0, 0.8, 0.5, 0.2, 0.01})
        CHECK(microfacet::fresnel_conductor(c, 1.5, 0.0) == Approx(microfacet::fresnel_dielectric(c, 1.5)).epsilon(1e-9));
    CHECK(microfacet::fresnel_conductor(1.0, 0.2, 3.0) == Approx((0.64 + 9.0) / (1.44 + 9.0)).epsilon(1e-12));
    CHECK(microfacet::fresnel_conductor(0.0, 0.2, 3.0) == Approx(1.0));
}

TEST_CASE("model strings name lobes, repeat counts and parameters", "[lobes][model]") {
    const Model m = Model::parse("lambert+ggx+ggx");
    REQUIRE(m.terms().size() == 3);
    CHECK(m.size() == 3 + 5 + 5);
    CHECK(m.name(0) == "lambert.rho_r");
    CHECK(m.name(3) == "ggx1.ks_r");
    CHECK(m.name(6) == "ggx1.alpha");
    CHECK(m.name(11) == "ggx2.alpha");
    CHECK(m.find("ggx2.f0") == 12);
    CHECK(m.find("ggx.alpha") == m.size());
    const Model l = Model::parse("lafortune3");
    CHECK(l.terms().size() == 3);
    CHECK(l.name(l.size() - 1) == "lafortune3.n");
    CHECK(Model::parse(" lambert + ggx ").text() == "lambert + ggx");
    for (const char* bad : {"", "+", "lambert+", "phong", "lafortune0", "lafortune99", "ggx+-ggx", "LAMBERT"})
        CHECK_THROWS_AS(Model::parse(bad), ValueError);

    CHECK_THROWS_AS(AnalyticBrdf("lambert", {0.5, 0.5}), ValueError);             // count
    CHECK_THROWS_AS(AnalyticBrdf("lambert", {0.5, 0.5, NAN}), ValueError);        // NaN
    CHECK_THROWS_AS(AnalyticBrdf("lambert", {0.5, 0.5, 1.5}), ValueError);        // out of bounds
    CHECK_THROWS_WITH(AnalyticBrdf("lambert+ggx", {0.5, 0.5, 0.5, 1, 1, 1, 0, 0.04}),
                      Catch::Contains("ggx.alpha"));
    const AnalyticBrdf lam("lambert", {0.2, 0.4, 0.6});
    CHECK(lam.nbytes() == 3 * sizeof(double));
    CHECK(lam.eval({0, 0, 1}, {0.6, 0, 0.8})[1] == Approx(0.4 / M_PI));
}
