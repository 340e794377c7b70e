#include <catch2/catch.hpp>

#include <array>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/sample/piecewise2d.h"
#include "brdfz/tabulate.h"
#include "brdfz/formats/io.h"
#include "detail/simd.h"
#include "detail/table_sample.h"
#include "sample_stats.h"
#include "test_util.h"

using namespace brdfz;

using test::check_sampler;
using test::random_views;

namespace {

// The half-vector sampler's density is smooth across the χ² cells (test::kSmoothPoints).
constexpr test::Chi2Setting kFineChi2{test::Draws::OneAtATime, 32, test::kSmoothPoints};

// A table sampled by the half-vector sampler, which these tests are about.
TabularBrdf tabulated(double alpha) {
    CoatedDiffuseParams p;
    p.alpha = alpha;
    return TabularBrdf(tabulate(CoatedDiffuse(p)).table, Lookup::Linear, SamplerKind::Fine);
}

}  // namespace

TEST_CASE("tabular sampler: chi-square, normalisation, round trip (glossy and near-specular)",
          "[sample][tabular][heavy]") {
    SECTION("glossy") { check_sampler(tabulated(0.12), 1000000, test::kViewsLevel, kFineChi2); }
    SECTION("near-specular") { check_sampler(tabulated(0.02), 1000000, test::kViewsLevel, kFineChi2); }
}

// The sanitizers' share of the test above: the glossy table, 2·10^5 draws.
TEST_CASE("tabular sampler: chi-square, normalisation, round trip (glossy, fewer draws)", "[sample][tabular][light]") {
    check_sampler(tabulated(0.12), 200000, test::kViewsLevel, kFineChi2);
}

namespace {

// n random (wo, u) on a sharp table: finite, non-negative pdfs and weights, few draws lost.
void check_random_draws(std::size_t n) {
    const TabularBrdf b = tabulated(0.05);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    std::normal_distribution<double> normal;
    std::size_t bad = 0, failed = 0;
    for (std::size_t k = 0; k < n; ++k) {
        Vec3 wo = normalize({normal(rng), normal(rng), normal(rng)});
        wo.z = std::fabs(wo.z);
        const BrdfSample s = b.sample(wo, u(rng), u(rng));
        failed += s.pdf == 0;
        bad += !(std::isfinite(s.pdf) && s.pdf >= 0 && std::isfinite(s.weight[0]) && std::isfinite(s.weight[1]) &&
                 std::isfinite(s.weight[2]) && s.weight[0] >= 0);
    }
    CHECK(bad == 0);
    CHECK(failed < n / 50);  // samples lost below the horizon stay rare
}

}  // namespace

TEST_CASE("tabular sampler: 10^7 random (wo, u) give finite, non-negative pdfs and weights",
          "[sample][tabular][heavy]") {
    check_random_draws(10000000);
}

// The sanitizers' share of the test above (the same draws, first 10^5).
TEST_CASE("tabular sampler: 10^5 random (wo, u) give finite, non-negative pdfs and weights",
          "[sample][tabular][light]") {
    check_random_draws(100000);
}

namespace {

// Every MERL table at 30 and 80 degrees (`both_views`), or at one of them, the tables taking them in turn.
void check_merl_samplers(bool both_views) {
    const auto files = test::merl_tables();
    if (files.empty()) {
        WARN("skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    bool grazing_turn = false;
    for (const auto& path : files) {
        INFO(path);
        const Loaded l = load(path.string());
        grazing_turn = !grazing_turn;
        for (double deg : {30.0, 80.0}) {
            if (!both_views && (deg == 80.0) != grazing_turn) continue;
            const Vec3 wo = spherical_direction(deg * M_PI / 180, 1.0);
            const test::Chi2Result r = test::chi2_test(*l.brdf, wo, 300000, 32, 1, test::Draws::Batch);
            CHECK(r.p_value > 0.001);
            CHECK(r.integral == Approx(1.0).margin(0.01));
        }
    }
}

}  // namespace

// The test below samples every table at one of the two views.
TEST_CASE("tabular sampler on real MERL tables", "[sample][data][heavy]") {
    check_merl_samplers(true);
}

TEST_CASE("tabular sampler on real MERL tables, one view each", "[sample][data][light]") {
    check_merl_samplers(false);
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

TEST_CASE("sampler_variance_ratio: near-ideal samplers compare as equal, a poor one does not", "[sample]") {
    const double theta_o = 60.0 * M_PI / 180.0;
    // A Lambertian tabulated: its half-vector sampler's weights spread by ~5 % where cosine
    // sampling's are constant. The stability study's old ratio of spreads (each + 0.01) made that a
    // 6-fold "variance blow-up"; against the floor it is no worse than cosine.
    TabulateOptions o;
    o.grid = GridSpec{45, 45, 90};
    const TabularBrdf diffuse(tabulate(AnalyticBrdf("lambert", {0.6, 0.5, 0.4}), o).table, Lookup::Linear,
                              SamplerKind::Fine);
    const SampledAlbedo a = sampled_albedo(diffuse, theta_o, 20000, 11);
    const double spread = a.stderr_[1] * std::sqrt(20000.0) / a.mean[1];
    INFO("relative spread " << spread);
    REQUIRE(spread > 0.01);  // not ideal: the comparison is not trivially 1
    CHECK(sampler_variance_ratio(diffuse, theta_o, 20000) < 1.5);
    // Draws from a glossy table's sampler while the BRDF is Lambertian: far worse than cosine.
    class Glossy final : public Brdf {
    public:
        explicit Glossy(const TabularBrdf& t) : t_(t) {}
        int channels() const override { return 3; }
        std::size_t nbytes() const override { return 0; }
        std::string describe() const override { return "lambertian sampled as a glossy coat"; }

    protected:
        Rgb eval_above(const Vec3&, const Vec3&) const override { return {0.2, 0.2, 0.2}; }
        BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override {
            BrdfSample s = t_.sample(wo, u1, u2);
            s.weight = {};
            return s;
        }

    private:
        const TabularBrdf& t_;
    };
    const TabularBrdf glossy = tabulated(0.05);
    CHECK(sampler_variance_ratio(Glossy(glossy), theta_o, 20000) > 10.0);
    // A glossy table's own sampler beats cosine sampling.
    CHECK(sampler_variance_ratio(glossy, theta_o, 20000) < 1.0);
    CHECK_THROWS_AS(sampler_variance_ratio(diffuse, 2.0, 100), ValueError);
    CHECK_THROWS_AS(sampler_variance_ratio(diffuse, theta_o, 1), ValueError);
    CHECK_THROWS_AS(sampler_variance_ratio(diffuse, theta_o, 100, -1.0), ValueError);
}

TEST_CASE("batch sampling gives what one-at-a-time sampling gives", "[sample]") {
    const TabularBrdf t = tabulated(0.05);
    const AnalyticBrdf a("lambert+ggx", {0.2, 0.3, 0.4, 0.9, 0.9, 0.9, 0.1, 0.04});
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(0, 1);
    std::normal_distribution<double> n;
    const std::size_t count = 1000;  // several blocks of the batch path, and a partial one
    std::vector<Vec3> wo(count);
    std::vector<std::array<double, 2>> us(count);
    for (std::size_t k = 0; k < count; ++k) {
        wo[k] = normalize({n(rng), n(rng), n(rng)});
        if (k % 3) wo[k].z = std::fabs(wo[k].z);  // a third below the horizon: failed samples in the batch
        us[k] = {u(rng), u(rng)};
    }
    for (const Brdf* b : {static_cast<const Brdf*>(&t), static_cast<const Brdf*>(&a)}) {
        INFO(b->describe());
        std::vector<BrdfSample> out(count);
        b->sample(wo, us, out);
        for (std::size_t k = 0; k < count; ++k) {
            const BrdfSample s = b->sample(wo[k], us[k][0], us[k][1]);
            REQUIRE(out[k].pdf == s.pdf);
            REQUIRE(out[k].wi.x == s.wi.x);
            for (int c = 0; c < 3; ++c) REQUIRE(out[k].weight[c] == Approx(s.weight[c]).epsilon(1e-12));
        }
    }
    std::vector<BrdfSample> short_out(count - 1);
    CHECK_THROWS_AS(t.sample(wo, us, short_out), ValueError);
}

// The CDF searches start from guide tables: the cell found must be the one inversion defines, on a
// grid with empty rows, empty cells and a spike, for u on a fine lattice (so on and next to CDF steps).
TEST_CASE("Piecewise2D: sampling by inversion with guide tables lands in the right cells", "[sample]") {
    const int rows = 7, cols = 9;
    std::vector<float> w(rows * cols);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    for (float& x : w) x = u01(rng) < 0.3f ? 0.0f : u01(rng);
    for (int c = 0; c < cols; ++c) w[2 * cols + c] = 0.0f;  // an empty row
    w[5 * cols + 4] = 200.0f;                            // a spike
    const Piecewise2D d(w, rows, cols);
    double total = 0.0;
    for (float x : w) total += x;
    const int n = 1000;  // u on an n × n lattice: cell counts approach n² · weight share
    std::vector<double> count(rows * cols, 0.0);
    double prev_y = -1.0;
    for (int i = 0; i < n; ++i) {
        double prev_x = -1.0;
        for (int j = 0; j < n; ++j) {
            const Piecewise2D::Point p = d.sample((i + 0.5) / n, (j + 0.5) / n);
            const int r = static_cast<int>(p.y * rows), c = static_cast<int>(p.x * cols);
            REQUIRE(w[r * cols + c] > 0.0f);  // never an empty cell
            REQUIRE(p.pdf == d.pdf(p.x, p.y));
            REQUIRE(p.x >= prev_x);  // monotone in u2 within a row
            prev_x = p.x;
            if (j == 0) {
                REQUIRE(p.y >= prev_y);  // and the row's coordinate monotone in u1
                prev_y = p.y;
            }
            count[r * cols + c] += 1.0;
        }
    }
    for (int k = 0; k < rows * cols; ++k) {
        INFO("cell " << k);
        CHECK(count[k] / (double(n) * n) == Approx(w[k] / total).margin(3.0 / n));
    }
}

// The tabular weight is looked up at bin coordinates from the draw's own angles (detail/table_sample.h),
// not from wi and wo as eval does: both must name the same point of the table, and the weight must be
// eval's f·cosθi/pdf, for either lookup, on synthetic and real data.
TEST_CASE("tabular sample: the weight from the draw's angles is eval's", "[sample][tabular]") {
    std::vector<std::pair<std::string, std::unique_ptr<Brdf>>> tables;
    tables.emplace_back("coated diffuse alpha 0.05", std::make_unique<TabularBrdf>(tabulated(0.05)));
    {  // a warped θd axis: the draw's θd maps to the table's coordinate as eval's does
        CoatedDiffuseParams p;
        p.alpha = 0.05;
        TabulateOptions o;
        o.grid = GridSpec{45, 30, 90};
        o.grid.theta_d_warp = 0.8;
        tables.emplace_back("coated diffuse alpha 0.05, 45x30x90, θd warp 0.8",
                            std::make_unique<TabularBrdf>(tabulate(CoatedDiffuse(p), o).table, Lookup::Linear,
                                                          SamplerKind::Fine));
    }
    const auto files = test::merl_tables();
    if (files.empty())
        WARN("real-data part skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
    else {  // the sharpest material when it is there
        const auto chrome = std::find_if(files.begin(), files.end(), [](const auto& p) { return p.stem() == "chrome"; });
        const std::string path = (chrome != files.end() ? *chrome : files.front()).string();
        LoadOptions fine;
        fine.sampler = SamplerKind::Fine;
        tables.emplace_back(path, load(path, fine).brdf);
    }
    for (auto& [name, brdf] : tables) {
        auto& t = dynamic_cast<TabularBrdf&>(*brdf);
        INFO(name);
        const GridSpec& g = t.table().grid();
        std::mt19937_64 rng(12);
        std::uniform_real_distribution<double> u(0, 1);
        std::normal_distribution<double> nd;
        double worst_coord = 0.0, worst_phi = 0.0, worst_weight = 0.0;
        int half = 0;
        for (int k = 0; k < 200000; ++k) {
            Vec3 wo = normalize({nd(rng), nd(rng), nd(rng)});
            wo.z = std::fabs(wo.z);
            const double u1 = u(rng), u2 = u(rng);
            const HalfVectorSampler::Draw d = t.sampler().fine()->draw(wo, u1, u2);
            if (!(d.half && d.sample.pdf > 0)) continue;
            ++half;
            const detail::BinCoords a = detail::drawn_bin_coords(g, d), b = detail::fast_bin_coords(g, d.sample.wi, wo);
            REQUIRE((a.up > g.n_phi_d) == (b.up > g.n_phi_d));  // flagged ill-conditioned alike
            if (b.up > g.n_phi_d) continue;
            worst_coord = std::max({worst_coord, std::fabs(a.uh - b.uh), std::fabs(a.ud - b.ud)});
            // φd is periodic (0 and n are one point), and fast_bin_coords has it only to rounding over
            // sinθh·sinθd (its cross products cancel): compared in bins times both sines.
            const double dp = std::fabs(a.up - b.up), sin_d = std::sin(b.ud / g.n_theta_d * M_PI / 2);
            worst_phi = std::max(worst_phi, std::min(dp, g.n_phi_d - dp) * sin_d * d.sin_h);
            const BrdfSample s = t.sample(wo, u1, u2);
            REQUIRE(s.pdf == d.sample.pdf);
            const Rgb f = t.eval(s.wi, wo);
            for (int c = 0; c < 3; ++c) {
                const double expect = f[c] * s.wi.z / s.pdf;
                if (expect > 0) worst_weight = std::max(worst_weight, std::fabs(s.weight[c] - expect) / expect);
                else REQUIRE(s.weight[c] == 0.0);
            }
        }
        INFO("largest difference: θh, θd " << worst_coord << " bins, φd " << worst_phi << " bins·sinθh·sinθd, weight "
                                            << worst_weight << " relative");
        CHECK(half > 150000);
        CHECK(worst_coord < 1e-9);
        CHECK(worst_phi < 1e-11);
        CHECK(worst_weight < 1e-10);
        // Nearest lookup: the bin eval picks, so the weight is eval's exactly (set_weight's rounding:
        // cosθi/pdf once, then per channel).
        t.set_lookup(Lookup::Nearest);
        for (int k = 0; k < 20000; ++k) {
            Vec3 wo = normalize({nd(rng), nd(rng), nd(rng)});
            wo.z = std::fabs(wo.z);
            const BrdfSample s = t.sample(wo, u(rng), u(rng));
            if (s.pdf == 0) continue;
            const Rgb f = t.eval(s.wi, wo);
            for (int c = 0; c < 3; ++c) REQUIRE(s.weight[c] == f[c] * (s.wi.z / s.pdf));
        }
        t.set_lookup(Lookup::Linear);
    }
}

// The fused batch kernels of both table classes against their one-at-a-time path, with bad input mixed in.
TEST_CASE("table sample_batch: each result is the one-at-a-time sample, and bad input gives failed samples",
          "[sample][tabular][compact][qemu]") {
    TabularBrdf t = tabulated(0.05);
    const Compressed u8 = compress(t, "tabular:res=45x45x90,dtype=u8log");
    const double nan = std::nan(""), inf = INFINITY;
    auto [wo, us] = random_views(700, 21);
    const std::size_t count = wo.size();
    wo[3] = {nan, 0.0, 1.0}, wo[4] = {0.0, 0.0, nan}, wo[5] = {inf, 0.0, 1.0}, wo[6] = {0.0, 0.0, -1.0};
    wo[7] = {0.0, 0.0, 1.0}, us[7] = {0.5, 0.3};  // the pole (wo's azimuth undefined), a data draw
    us[8] = {nan, 0.5}, us[9] = {0.5, inf}, us[10] = {1.0, 0.5}, us[11] = {-0.1, 0.5};
    // The batch kernel is built twice (detail/simd.h), both without FMA: each gives sample()'s results.
    if (detail::simd_level() < detail::Simd::Avx2Fma) WARN("no AVX2 on this CPU: both runs use the SSE2 kernel");
    // The float32 table also with nearest lookup (the kernel's other branch).
    for (const auto& [b, simd, lookup] :
         {std::tuple{static_cast<const Brdf*>(&t), detail::Simd::Avx2Fma, Lookup::Linear},
          std::tuple{static_cast<const Brdf*>(&t), detail::Simd::Sse2, Lookup::Linear},
          std::tuple{static_cast<const Brdf*>(&t), detail::Simd::Avx2Fma, Lookup::Nearest},
          std::tuple{static_cast<const Brdf*>(&t), detail::Simd::Sse2, Lookup::Nearest},
          std::tuple{static_cast<const Brdf*>(u8.brdf.get()), detail::Simd::Avx2Fma, Lookup::Linear},
          std::tuple{static_cast<const Brdf*>(u8.brdf.get()), detail::Simd::Sse2, Lookup::Linear}}) {
        t.set_lookup(b == &t ? lookup : Lookup::Linear);
        INFO(b->describe() << (simd == detail::Simd::Sse2 ? ", SSE2 kernel" : ", AVX2 kernel"));
        std::vector<BrdfSample> out(count);
        detail::simd_cap = simd;
        b->sample(wo, us, out);
        detail::simd_cap = detail::Simd::Avx512;
        for (std::size_t k = 0; k < count; ++k) {
            INFO(k);
            const BrdfSample s = b->sample(wo[k], us[k][0], us[k][1]);
            detail::simd_cap = detail::Simd::Sse2;  // the one-at-a-time sample has both builds too
            const BrdfSample s_sse2 = b->sample(wo[k], us[k][0], us[k][1]);
            detail::simd_cap = detail::Simd::Avx512;
            REQUIRE(out[k].pdf == s.pdf);
            REQUIRE(s_sse2.pdf == s.pdf);
            REQUIRE(std::isfinite(s.pdf));
            if (k == 4 || k == 6 || (k >= 8 && k <= 11)) REQUIRE(s.pdf == 0.0);  // outside sample()'s domain
            if (s.pdf == 0.0) continue;
            REQUIRE(out[k].wi.x == s.wi.x);
            REQUIRE(out[k].wi.y == s.wi.y);
            REQUIRE(out[k].wi.z == s.wi.z);
            REQUIRE(s_sse2.wi.x == s.wi.x);
            REQUIRE(s_sse2.wi.y == s.wi.y);
            REQUIRE(s_sse2.wi.z == s.wi.z);
            for (int c = 0; c < 3; ++c) {
                REQUIRE(std::isfinite(s.weight[c]));
                REQUIRE(out[k].weight[c] == s.weight[c]);
                REQUIRE(s_sse2.weight[c] == s.weight[c]);
            }
        }
        CHECK(out[7].pdf > 0.0);
    }
}

// draw_block searches the CDFs across draws in two steps of the guided scan and hands longer scans
// (and cell coordinates needing a nudge) to Piecewise2D::sample: every draw must still be draw()'s,
// angles included, in both builds. A near-specular table has the steepest CDFs (the longest scans).
TEST_CASE("HalfVectorSampler::draw_block: each draw is draw()'s, in every build", "[sample][tabular][kernels][qemu]") {
    const TabularBrdf t = tabulated(0.02);
    const HalfVectorSampler& sampler = *t.sampler().fine();
    auto [wo, us] = random_views(20000, 31);
    const std::size_t count = wo.size();
    us[1] = {0.999999999, 0.9999999999};  // u rounding to 1 in float: the scans' last intervals
    us[2] = {0.5, INFINITY}, us[3] = {2.0, 0.5}, wo[4] = {0.0, 0.0, -1.0};
    for (detail::Simd simd : test::simd_levels()) {
        INFO(test::simd_label(simd) << " build");
        std::size_t half = 0;
        HalfVectorSampler::Draws block;
        for (std::size_t start = 0; start < count; start += HalfVectorSampler::kBlock) {
            const std::size_t m = std::min(HalfVectorSampler::kBlock, count - start);
            detail::simd_cap = simd;
            sampler.draw_block(wo.data() + start, us.data() + start, m, block);
            detail::simd_cap = detail::Simd::Avx512;
            for (std::size_t i = 0; i < m; ++i) {
                const std::size_t k = start + i;
                INFO(k);
                const HalfVectorSampler::Draw d = Brdf::can_draw(wo[k], us[k][0], us[k][1])
                                                      ? sampler.draw(wo[k], us[k][0], us[k][1])
                                                      : HalfVectorSampler::Draw{};
                REQUIRE(block.pdf[i] == d.sample.pdf);
                if (d.sample.pdf == 0.0) continue;
                REQUIRE(block.wi_x[i] == d.sample.wi.x);
                REQUIRE(block.wi_y[i] == d.sample.wi.y);
                REQUIRE(block.wi_z[i] == d.sample.wi.z);
                REQUIRE(block.half[i] == d.half);
                if (!d.half) continue;
                ++half;
                REQUIRE(block.sin_h[i] == d.sin_h);
                REQUIRE(block.cos_h[i] == d.cos_h);
                REQUIRE(block.sin_p[i] == d.sin_p);
                REQUIRE(block.cos_p[i] == d.cos_p);
                REQUIRE(block.sin_o[i] == d.sin_o);
                REQUIRE(block.cos_o[i] == d.cos_o);
            }
        }
        CHECK(half > count * 9 / 10);
    }
}

TEST_CASE("half-vector sampler: resolutions whose stacked tables exceed int indices are refused up front",
          "[sample]") {
    const AnalyticBrdf lambert("lambert", {0.5, 0.5, 0.5});
    HalfVectorSamplerOptions o;
    o.n_theta_o = 1024, o.n_theta_h = 4096, o.n_phi = 1024;  // each within its own bound: 4.3e9 CDF entries
    CHECK_THROWS_AS(HalfVectorSampler(lambert, o), ValueError);
}
