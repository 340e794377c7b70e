#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <random>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "detail/simd.h"
#include "sample_stats.h"
#include "simd_levels.h"
#include "test_util.h"

using namespace brdfz;

namespace {

// A glossy coated diffuse tabulated on a grid: its below-horizon bins are invalid (masked).
Table coated(const GridSpec& g, double alpha = 0.12) {
    CoatedDiffuseParams p;
    p.alpha = alpha;
    TabulateOptions o;
    o.grid = g;
    return tabulate(CoatedDiffuse(p), o).table;
}

// Positive, smooth, every bin valid, not of low rank.
Table dense(const GridSpec& g) {
    Table t(g);
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const double x = 2.0 + std::sin(1.3 * ih + 0.7 * id * id) + 0.5 * std::cos(ip * (ih + 1.0) / 3.0);
                t.set(g.index(ih, id, ip), {0.1 + x, 0.2 + 0.5 * x * x, 0.05 + std::exp(-0.1 * ih * id)});
            }
    return t;
}

FactorOptions options(FactorMethod method, int rank, FactorSpace space = FactorSpace::Linear,
                      FactorLayout layout = FactorLayout::HxDP, FactorColour colour = FactorColour::Separate) {
    FactorOptions o;
    o.method = method;
    o.rank = rank;
    o.space = space;
    o.layout = layout;
    o.colour = colour;
    o.max_iterations = method == FactorMethod::Nmf ? 100 : 50;
    return o;
}

// sqrt(Σ (a − b)² / Σ b²) over the bins valid in `ref`, all channels.
double relative_error(const Table& approx, const Table& ref) {
    double num = 0.0, den = 0.0;
    for (std::size_t bin = 0; bin < ref.bins(); ++bin) {
        if (!ref.valid(bin)) continue;
        for (int c = 0; c < 3; ++c) {
            const double d = double(approx.at(bin, c)) - ref.at(bin, c);
            num += d * d;
            den += double(ref.at(bin, c)) * ref.at(bin, c);
        }
    }
    return std::sqrt(num / den);
}

Vec3 random_direction(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    return normalize(Vec3{n(rng), n(rng), n(rng)});
}

}  // namespace

TEST_CASE("factored: full-rank svd reproduces the table to 1e-6 relative", "[factored][svd]") {
    const GridSpec g{8, 6, 12};
    const Table t = dense(g);
    for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP})
        for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Log, FactorSpace::Cbrt}) {
            INFO(factor_layout_name(layout) << " " << factor_space_name(space));
            const int full = layout == FactorLayout::HxDP ? 8 : 12;
            const Factored f = factor(t, options(FactorMethod::Svd, full, space, layout));
            std::size_t clamped = 99;
            CHECK(relative_error(f.brdf->reconstruct(&clamped), t) < 1e-6);
            CHECK(clamped == 0);
            CHECK(f.report.valid_bins == g.bins());
        }
    // Shared colour at full rank is exact when the colour is one per table (channels scaled copies).
    Table grey(g);
    for (std::size_t bin = 0; bin < g.bins(); ++bin) {
        const double x = t.at(bin, 0);
        grey.set(bin, {0.8 * x, 0.5 * x, 0.1 * x});
    }
    const Factored f = factor(grey, options(FactorMethod::Svd, 8, FactorSpace::Linear, FactorLayout::HxDP,
                                            FactorColour::Shared));
    CHECK(relative_error(f.brdf->reconstruct(), grey) < 1e-6);
}

TEST_CASE("factored: full-rank svd of a masked table reproduces every valid bin", "[factored][svd][mask]") {
    const Table t = coated({6, 8, 16});
    REQUIRE(t.valid_bins() < t.bins());  // below-horizon bins are masked
    const Factored f = factor(t, options(FactorMethod::Svd, 6, FactorSpace::Log));
    CHECK(relative_error(f.brdf->reconstruct(), t) < 1e-5);
}

TEST_CASE("factored: error falls monotonically with rank", "[factored][heavy]") {
    const Table t = coated({24, 24, 48});
    for (FactorMethod method : {FactorMethod::Svd, FactorMethod::Nmf})
        for (FactorSpace space : {FactorSpace::Log, FactorSpace::Cos}) {
            INFO(factor_method_name(method) << " " << factor_space_name(space));
            double previous = std::numeric_limits<double>::infinity();
            for (int rank = 1; rank <= 5; ++rank) {
                // Weighted problems converge slowly (cos: ~100 iterations at rank 3); a solver stopped
                // early is not the property under test.
                FactorOptions o = options(method, rank, space);
                o.max_iterations = 300;
                const Factored f = factor(t, o);
                INFO("rank " << rank << " residual " << f.report.residual);
                CHECK(f.report.residual < previous);
                previous = f.report.residual;
            }
        }
}

TEST_CASE("factored: nmf factors and reconstructions are non-negative", "[factored][nmf][heavy]") {
    const Table t = coated({16, 16, 32}, 0.05);
    for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Cos, FactorSpace::Log, FactorSpace::Cbrt})
        for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared}) {
            INFO(factor_space_name(space) << " " << factor_colour_name(colour));
            const Factored f = factor(t, options(FactorMethod::Nmf, 3, space, FactorLayout::HxDP, colour));
            const Factors& x = f.brdf->factors();
            for (const std::vector<float>* values : {&x.u, &x.v, &x.colour_weights})
                for (float v : *values) REQUIRE(v >= 0.0f);
            CHECK(f.report.clamped == 0);
            CHECK(f.report.residual < 0.5);
        }
}

namespace {

// Both methods with both colour modes (`all`), or svd separate and nmf shared.
void check_mask_ignores_fills(bool all) {
    const GridSpec g{12, 12, 24};
    Table t = coated(g);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<std::size_t> invalid;
    for (std::size_t bin = 0; bin < t.bins(); ++bin) {
        if (t.valid(bin) && u(rng) < 0.2) t.invalidate(bin);
        if (!t.valid(bin)) invalid.push_back(bin);
    }
    // The same masked bins holding other invalid contents: negative, infinite, a huge negative value
    // in one channel only (the others plausible).
    const float inf = std::numeric_limits<float>::infinity();
    const Rgb fills[] = {{-1.0, -2.0, -3.0}, {inf, inf, inf}, {0.5, -1e30, 0.5}, {inf, 0.2, -0.0001}};
    for (FactorMethod method : {FactorMethod::Svd, FactorMethod::Nmf})
        for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared}) {
            if (!all && (method == FactorMethod::Nmf) != (colour == FactorColour::Shared)) continue;
            INFO(factor_method_name(method) << " " << factor_colour_name(colour));
            const FactorOptions o = options(method, 3, FactorSpace::Cbrt, FactorLayout::HDxP, colour);
            const Factored ref = factor(t, o);
            for (const Rgb& fill : fills) {
                Table other = t;
                for (std::size_t bin : invalid) other.set(bin, fill);
                const Factored f = factor(other, o);
                CHECK(f.brdf->factors().u == ref.brdf->factors().u);
                CHECK(f.brdf->factors().v == ref.brdf->factors().v);
                CHECK(f.brdf->factors().colour_weights == ref.brdf->factors().colour_weights);
            }
        }
}

}  // namespace

// The test below runs svd separate and nmf shared: both methods, both colour modes, every fill.
TEST_CASE("factored: masked factorisation is unaffected by the values in invalid bins", "[factored][mask][heavy]") {
    check_mask_ignores_fills(true);
}

TEST_CASE("factored: masked factorisation is unaffected by the values in invalid bins (two of the four cases)",
          "[factored][mask][light]") {
    check_mask_ignores_fills(false);
}

TEST_CASE("factored: a masked low-rank table is completed, not pulled towards zero", "[factored][mask]") {
    // Exactly rank 2 in linear space; 30% of the bins masked. Zero-filling would pull the factors
    // towards 0 there; the weighted factorisation recovers the masked values.
    const GridSpec g{16, 10, 20};
    Table full(g);
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const double a = 1.0 + ih, b = 2.0 + std::sin(id + 0.3 * ip), c = 0.5 + 0.1 * ih * ih, d = 1.0 + 0.2 * ip;
                const double x = a * b + c * d;
                full.set(g.index(ih, id, ip), {x, 2.0 * x, 0.5 * x});
            }
    Table masked = full;
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(0, 1);
    for (std::size_t bin = 0; bin < masked.bins(); ++bin)
        if (u(rng) < 0.3) masked.invalidate(bin);
    for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared}) {
        INFO(factor_colour_name(colour));
        FactorOptions o = options(FactorMethod::Svd, 2, FactorSpace::Linear, FactorLayout::HxDP, colour);
        o.max_iterations = 500;
        const Factored f = factor(masked, o);
        CHECK(relative_error(f.brdf->reconstruct(), full) < 1e-4);
    }
}

namespace {

// Every bin of the reconstruction (the invalid ones too, which eval blends in near the horizon) is
// finite and at most the data's largest value per channel; so is eval, and the sampler builds.
void check_bounded(const FactoredBrdf& f, const Table& t) {
    const Table back = f.reconstruct();
    float top[3] = {0.0f, 0.0f, 0.0f};
    for (std::size_t bin = 0; bin < t.bins(); ++bin)
        if (t.valid(bin))
            for (int c = 0; c < 3; ++c) top[c] = std::max(top[c], t.at(bin, c));
    for (int c = 0; c < 3; ++c) CHECK(f.factors().max_value[c] == top[c]);
    std::size_t out_of_range = 0;  // the ceiling goes through the transform and back: allow rounding
    for (std::size_t bin = 0; bin < back.bins(); ++bin)
        for (int c = 0; c < 3; ++c)
            out_of_range += !(std::isfinite(back.at(bin, c)) && back.at(bin, c) <= top[c] * (1.0 + 1e-6));
    CHECK(out_of_range == 0);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const Vec3 wo = spherical_direction(1.2, 0.3);
    for (int k = 0; k < 1000; ++k) {
        const BrdfSample s = f.sample(wo, u(rng), u(rng));  // builds the sampler: throws on a non-finite value
        REQUIRE(std::isfinite(s.pdf));
        for (double w : s.weight) REQUIRE(std::isfinite(w));
    }
}

}  // namespace

TEST_CASE("factored: bins without data do not extrapolate beyond the data (log and cbrt spaces)",
          "[factored][mask][heavy]") {
    // A sharp coat's grazing bins are below the horizon (invalid); with one θh row entirely invalid
    // as well. Unregularised, rank 4 reconstructed log-space values of 490–630 there (expm1: beyond
    // any float) and cbrt values up to 1,200, against data at most 8.9 and 19.
    Table t = coated({16, 16, 32}, 0.05);
    const GridSpec& g = t.grid();
    for (int id = 0; id < g.n_theta_d; ++id)
        for (int ip = 0; ip < g.n_phi_d; ++ip) t.invalidate(g.index(15, id, ip));
    for (FactorMethod method : {FactorMethod::Svd, FactorMethod::Nmf})
        for (FactorSpace space : {FactorSpace::Log, FactorSpace::Cbrt}) {
            INFO(factor_method_name(method) << " " << factor_space_name(space));
            FactorOptions o = options(method, 4, space);
            o.max_iterations = 100;
            const Factored f = factor(t, o);
            check_bounded(*f.brdf, t);
            // The regularisation costs the valid bins little: the unregularised residuals were 0.0049
            // (svd, log), 0.0066 (nmf, log), 0.0011 (svd, cbrt), 0.0032 (nmf, cbrt).
            CHECK(f.report.residual < (space == FactorSpace::Log ? 0.01 : 0.005));
        }
}

TEST_CASE("factored: RGL cc_ibiza_sunset factors to a finite sampler (nmf and svd)", "[factored][data][heavy]") {
    const std::filesystem::path file = test::rgl_file("cc_ibiza_sunset");
    if (!std::filesystem::exists(file)) {
        WARN("skipped: " << file << " is missing");
        return;
    }
    // Its RGL extrapolation reaches 1.7e7 at θd ≈ 89°; unregularised, nmf rank 2 in log space then
    // reconstructed 1.1e5 (log space) in the bins without data and the sampler's build threw
    // "piecewise2d: weights must be finite and >= 0".
    const Loaded l = load(file.string());
    TabulateOptions to;
    to.grid = GridSpec{90, 90, 180, BinPosition::Centre};
    const Table t = tabulate(*l.brdf, to).table;
    for (const char* spec : {"nmf:rank=2", "svd:rank=4,space=log"}) {
        INFO(spec);
        const Compressed c = compress(TabularBrdf(t), spec);
        check_bounded(dynamic_cast<const FactoredBrdf&>(*c.brdf), t);
    }
}

TEST_CASE("factored: a warped θd axis lowers the error on RGL satin_rosaline", "[factored][data][rgl][warp]") {
    const std::filesystem::path file = test::rgl_file("satin_rosaline");
    if (!std::filesystem::exists(file)) {
        WARN("skipped: " << file << " is missing");
        return;
    }
    const Loaded l = load(file.string());
    MetricOptions coarse;  // half the metric grid's resolution on each axis: an eighth of the points
    coarse.grid = GridSpec{45, 45, 90, BinPosition::Start};
    // On the full φd circle (a reciprocal grid holds the mean of the two sides, which the metric grid's
    // one-sided reference counts as error), 14,520 bytes either way.
    const Compressed linear = compress(*l.brdf, "svd:rank=6,space=cos,colour=shared,res=90x16x32,symmetry=none");
    const Compressed warped =
        compress(*l.brdf, "svd:rank=6,space=cos,colour=shared,res=90x16x32,dwarp=0.9,symmetry=none");
    CHECK(warped.brdf->nbytes() == 14520);
    CHECK(warped.brdf->nbytes() == linear.brdf->nbytes());
    const Metrics m = compare(*l.brdf, *warped.brdf, coarse);
    const double e_linear = compare(*l.brdf, *linear.brdf, coarse).cos_rmse_rel.mean, e_warped = m.cos_rmse_rel.mean;
    CAPTURE(e_linear, e_warped);
    CHECK(e_warped < 0.6 * e_linear);  // on this coarser metric grid: 9.6 % -> 5.2 %
    CHECK(e_warped < 0.06);
}

namespace {

void check_random_pairs(std::size_t n) {
    const Table t = coated({16, 16, 32}, 0.03);
    std::mt19937_64 rng(11);
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = random_direction(rng);  // half of them below the horizon
        wo[k] = random_direction(rng);
    }
    wi[0] = {0, 0, 1}, wo[0] = {0, 0, 1};  // the pole, where φd is undefined
    wi[1] = {1, 0, 0}, wo[1] = {-1, 0, 0};  // grazing, opposite
    wi[2] = {std::nan(""), 0, 1};
    std::vector<Rgb> out(n);
    for (FactorMethod method : {FactorMethod::Svd, FactorMethod::Nmf})
        for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Log})
            for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP}) {
                INFO(factor_method_name(method) << " " << factor_space_name(space) << " " << factor_layout_name(layout));
                const Factored f = factor(t, options(method, 2, space, layout));
                f.brdf->eval(wi, wo, out);
                std::size_t bad = 0, zeros = 0;
                for (std::size_t k = 0; k < n; ++k)
                    for (int c = 0; c < 3; ++c) {
                        bad += !(std::isfinite(out[k][c]) && out[k][c] >= 0.0);
                        zeros += wi[k].z > 0 && wo[k].z > 0 && out[k][c] == 0.0;
                    }
                CHECK(bad == 0);
                // Every clamped value is an exact 0 (nmf factors may give exact zeros unclamped), and
                // nmf never clamps; this low-rank linear svd does, somewhere.
                const std::uint64_t clamped = f.brdf->clamped_evaluations();
                CHECK(clamped <= zeros);
                if (method == FactorMethod::Nmf) CHECK(clamped == 0);
                if (method == FactorMethod::Svd && space == FactorSpace::Linear) CHECK(clamped > 0);
                // Single-pair eval is the batch kernel's arithmetic.
                // and counts its clamps too: evaluating the batch pair by pair doubles the count.
                std::size_t differ = 0;
                for (std::size_t k = 0; k < n; ++k) {
                    const Rgb one = f.brdf->eval(wi[k], wo[k]);
                    differ += std::memcmp(&one, &out[k], sizeof one) != 0;
                }
                CHECK(differ == 0);
                CHECK(f.brdf->clamped_evaluations() == 2 * clamped);
            }
}

}  // namespace

// The test below evaluates the first 10^5 of the same pairs, every case.
TEST_CASE("factored: outputs are finite and non-negative on 10^6 random pairs, clamping counted", "[factored][heavy]") {
    check_random_pairs(1000000);
}

TEST_CASE("factored: outputs are finite and non-negative on 10^5 random pairs, clamping counted", "[factored][light]") {
    check_random_pairs(100000);
}

TEST_CASE("factored: eval interpolates the factors (bin samples give the reconstruction)", "[factored]") {
    const GridSpec g{10, 10, 20};
    const Factored f = factor(coated(g), options(FactorMethod::Svd, 3, FactorSpace::Log));
    const Table back = f.brdf->reconstruct();
    for (int ih : {1, 4, 8})
        for (int id : {0, 3, 7})
            for (int ip : {2, 11}) {
                const auto [wi, wo] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                if (!(wi.z > 0 && wo.z > 0)) continue;
                const Rgb e = f.brdf->eval(wi, wo);
                for (int c = 0; c < 3; ++c) CHECK(e[c] == Approx(back.at(g.index(ih, id, ip), c)).epsilon(1e-5));
            }
}

// The kernel blends factor rows in float32 and inverts the transform without libm; the reference is
// the tabular linear lookup (double arithmetic) of the transform-space reconstruction, mapped back
// with std: interpolating the factors is interpolating their product, as the lookup interpolates bins.
// That is the kernel's specification, and each of its builds this CPU runs (SSE2, AVX2 + FMA, AVX-512;
// NEON on ARM64) is checked against it. nmf, so that no value is clamped (clamping happens after the
// interpolation, not before).
namespace {

// Every space, layout and colour mode (`all`), or the half of the combinations with an even count of
// (non-linear space, HDxP, shared colour): each space, layout and colour mode is still among them.
void check_eval_interpolates(bool all) {
    const GridSpec g{12, 10, 16};
    const Table t = coated(g);
    std::mt19937_64 rng(12);
    const std::size_t n = 20000;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = random_direction(rng), wo[k] = random_direction(rng);
        wi[k].z = std::fabs(wi[k].z), wo[k].z = std::fabs(wo[k].z);
    }
    std::vector<Rgb> out(n), ref(n);
    for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Log, FactorSpace::Cbrt})
        for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP})
            for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared}) {
                const int odd = (space != FactorSpace::Linear) + (layout == FactorLayout::HDxP) + (colour == FactorColour::Shared);
                if (!all && odd % 2 != 0) continue;
                INFO(factor_space_name(space) << " " << factor_layout_name(layout) << " " << factor_colour_name(colour));
                // Without the ceiling at the data's maximum (tested on its own), which clamps after
                // the interpolation here but before it in the reference.
                Factors unbounded = factor(t, options(FactorMethod::Nmf, 3, space, layout, colour)).brdf->factors();
                unbounded.max_value = {Factors::kUnbounded, Factors::kUnbounded, Factors::kUnbounded};
                const FactoredBrdf reference_factors(unbounded);
                Table y = reference_factors.reconstruct();
                for (std::size_t bin = 0; bin < y.bins(); ++bin) {
                    Rgb v;
                    for (int c = 0; c < 3; ++c) {
                        const double x = y.at(bin, c);
                        v[c] = space == FactorSpace::Log ? std::log1p(x) : space == FactorSpace::Cbrt ? std::cbrt(x) : x;
                    }
                    y.set(bin, v);
                }
                TabularBrdf(std::move(y), Lookup::Linear).eval(wi, wo, ref);
                for (detail::Simd level : test::simd_levels()) {
                    INFO(test::simd_label(level));
                    // A FactoredBrdf picks its kernel's build when constructed.
                    const std::unique_ptr<FactoredBrdf> f = [&] {
                        const test::SimdCap cap(level);
                        return std::make_unique<FactoredBrdf>(unbounded);
                    }();
                    f->eval(wi, wo, out);
                    double worst = 0.0;
                    for (std::size_t k = 0; k < n; ++k)
                        for (int c = 0; c < 3; ++c) {
                            const double r = ref[k][c],
                                         v = space == FactorSpace::Log ? std::expm1(r) : space == FactorSpace::Cbrt ? r * r * r : r;
                            worst = std::max(worst, std::fabs(out[k][c] - v) / (std::fabs(v) + 1e-6));
                        }
                    CHECK(worst < 1e-5);
                    CHECK(f->clamped_evaluations() == 0);
                }
            }
}

}  // namespace

// The test below runs half of the combinations, each space, layout and colour mode among them.
TEST_CASE("factored: eval is the interpolated reconstruction, within 1e-5, at random pairs", "[factored][heavy]") {
    check_eval_interpolates(true);
}

TEST_CASE("factored: eval is the interpolated reconstruction, within 1e-5, at random pairs (half the cases)",
          "[factored][light][qemu]") {
    check_eval_interpolates(false);
}

// The kernel is built for each SIMD level (detail/simd.h): SSE2, AVX2 + FMA and AVX-512, the widest the
// CPU has chosen. They blend in float, so they agree to float rounding, not bit for bit (the wide ones fuse,
// lanes sum in another order); single-pair eval runs the batch's build, bit for bit, in each. nmf:
// without cancelling components, float rounding stays relative to each value.
namespace {

// Every space, layout and colour mode (`all`), or the half of them as in check_eval_interpolates:
// each space, and each layout with each colour mode (the kernel's builds), still among them.
void check_kernels_agree(bool all) {
    const std::vector<detail::Simd> levels = test::simd_levels();
    if (levels.size() == 1) WARN("no AVX2 + FMA on this CPU: every run uses the SSE2 kernel");
    const Table t = coated({12, 10, 16});
    std::mt19937_64 rng(13);
    const std::size_t n = 20000;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) wi[k] = random_direction(rng), wo[k] = random_direction(rng);
    std::vector<Rgb> wide(n), base(n);
    for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Log, FactorSpace::Cbrt})
        for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP})
            for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared}) {
                const int odd = (space != FactorSpace::Linear) + (layout == FactorLayout::HDxP) + (colour == FactorColour::Shared);
                if (!all && odd % 2 != 0) continue;
                INFO(factor_space_name(space) << " " << factor_layout_name(layout) << " " << factor_colour_name(colour));
                const Factored f = factor(t, options(FactorMethod::Nmf, 3, space, layout, colour));
                // A FactoredBrdf picks its kernel's build when constructed.
                const auto built_at = [&](detail::Simd level) {
                    const test::SimdCap cap(level);
                    return std::make_unique<FactoredBrdf>(f.brdf->factors());
                };
                built_at(detail::Simd::Sse2)->eval(wi, wo, base);
                for (detail::Simd level : levels) {
                    INFO(test::simd_label(level));
                    const std::unique_ptr<FactoredBrdf> b = built_at(level);
                    b->eval(wi, wo, wide);
                    double worst = 0.0;
                    std::size_t nonzero = 0, differ = 0;
                    for (std::size_t k = 0; k < n; ++k) {
                        for (int c = 0; c < 3; ++c) {
                            worst = std::max(worst, std::fabs(wide[k][c] - base[k][c]) / (std::fabs(base[k][c]) + 1e-12));
                            nonzero += base[k][c] > 0.0;
                        }
                        const Rgb one = b->eval(wi[k], wo[k]);
                        differ += std::memcmp(&one, &wide[k], sizeof one) != 0;
                    }
                    CHECK(nonzero > n / 2);  // a quarter of the pairs have both directions above
                    CHECK(worst < 2e-6);
                    CHECK(differ == 0);
                }
            }
}

}  // namespace

// The test below compares the kernels on half of the combinations.
TEST_CASE("factored: the SSE2, AVX2 and AVX-512 kernels agree", "[factored][heavy]") {
    check_kernels_agree(true);
}

TEST_CASE("factored: the SSE2, AVX2 and AVX-512 kernels agree (half the cases)", "[factored][light]") {
    check_kernels_agree(false);
}

// Separate colour of rank 3 and 4 runs a kernel of its own (channels in groups of 4 floats, no colour
// mix); the same factors as shared colour of rank 3·r with one-hot colour weights run the mixing
// kernel. Both builds, both layouts, every space: the two agree to float rounding.
TEST_CASE("factored: separate colour of rank 3 and 4 evaluates as its shared one-hot equivalent", "[factored][qemu]") {
    const GridSpec g{12, 10, 16};
    std::mt19937_64 rng(14);
    std::uniform_real_distribution<float> entry(0.05f, 0.6f);
    const std::size_t n = 5000;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = random_direction(rng), wo[k] = random_direction(rng);
        wi[k].z = std::fabs(wi[k].z), wo[k].z = std::fabs(wo[k].z);
    }
    std::vector<Rgb> grouped(n), mixed(n);
    for (detail::Simd simd : test::simd_levels())
        for (int rank : {3, 4})
            for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP})
                for (FactorSpace space : {FactorSpace::Linear, FactorSpace::Log, FactorSpace::Cbrt}) {
                    INFO(test::simd_label(simd) << " rank " << rank << " " << factor_layout_name(layout) << " "
                                                << factor_space_name(space));
                    Factors separate;
                    separate.grid = g, separate.space = space, separate.layout = layout, separate.rank = rank;
                    const std::size_t m = 3 * static_cast<std::size_t>(rank);
                    separate.u.resize(separate.rows() * m), separate.v.resize(separate.columns() * m);
                    for (float& x : separate.u) x = entry(rng);
                    for (float& x : separate.v) x = entry(rng);
                    Factors shared = separate;
                    shared.colour = FactorColour::Shared, shared.rank = 3 * rank;
                    shared.colour_weights.assign(3 * m, 0.0f);
                    for (std::size_t c = 0; c < 3; ++c)
                        for (std::size_t j = 0; j < static_cast<std::size_t>(rank); ++j)
                            shared.colour_weights[c * m + c * rank + j] = 1.0f;
                    detail::simd_cap = simd;
                    const FactoredBrdf a(std::move(separate)), b(std::move(shared));
                    detail::simd_cap = detail::Simd::Avx512;
                    a.eval(wi, wo, grouped);
                    b.eval(wi, wo, mixed);
                    double worst = 0.0;
                    std::size_t positive = 0;
                    for (std::size_t k = 0; k < n; ++k)
                        for (int c = 0; c < 3; ++c) {
                            worst = std::max(worst, std::fabs(grouped[k][c] - mixed[k][c]) / (mixed[k][c] + 1e-12));
                            positive += mixed[k][c] > 0.0;
                        }
                    CHECK(positive > n);  // most pairs, every channel: the factors are positive
                    CHECK(worst < 2e-6);
                }
}

// A table on a warped θd axis (table.h): full-rank factors reproduce it, eval reads bin i at the warped
// θd_at(i) (on the linear axis that direction lies in another bin), and between samples eval is the
// tabular linear lookup on the same warped grid.
TEST_CASE("factored: factors on a warped θd axis are sampled and interpolated on that axis", "[factored][warp]") {
    const GridSpec g{6, 10, 8, BinPosition::Centre, 0.8};
    const Table t = dense(g);
    const Factored f = factor(t, options(FactorMethod::Svd, 6));
    CHECK(f.brdf->factors().grid == g);
    CHECK(relative_error(f.brdf->reconstruct(), t) < 1e-6);
    int checked = 0;
    for (int id = 0; id < g.n_theta_d; ++id) {
        const auto [wi, wo] = from_half_diff({g.theta_h_at(0), 0.0, g.theta_d_at(id), g.phi_d_at(3)});
        if (!(wi.z > 0 && wo.z > 0)) continue;
        ++checked;
        const Rgb e = f.brdf->eval(wi, wo);
        for (int c = 0; c < 3; ++c) CHECK(e[c] == Approx(t.at(g.index(0, id, 3), c)).epsilon(1e-5));
    }
    CHECK(checked == g.n_theta_d);

    std::mt19937_64 rng(4);
    const std::size_t n = 5000;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = random_direction(rng), wo[k] = random_direction(rng);
        wi[k].z = std::fabs(wi[k].z), wo[k].z = std::fabs(wo[k].z);
    }
    std::vector<Rgb> out(n), ref(n), linear_axis(n);
    f.brdf->eval(wi, wo, out);
    const Table back = f.brdf->reconstruct();
    TabularBrdf(back, Lookup::Linear).eval(wi, wo, ref);
    Table relabelled(GridSpec{6, 10, 8}, Table::Uninitialized{});  // the same values read on the linear axis
    for (std::size_t bin = 0; bin < back.bins(); ++bin) relabelled.set(bin, {back.at(bin, 0), back.at(bin, 1), back.at(bin, 2)});
    TabularBrdf(std::move(relabelled), Lookup::Linear).eval(wi, wo, linear_axis);
    double worst = 0.0, worst_linear = 0.0;
    for (std::size_t k = 0; k < n; ++k)
        for (int c = 0; c < 3; ++c) {
            worst = std::max(worst, std::fabs(out[k][c] - ref[k][c]) / (std::fabs(ref[k][c]) + 1e-6));
            worst_linear = std::max(worst_linear, std::fabs(out[k][c] - linear_axis[k][c]) / (std::fabs(linear_axis[k][c]) + 1e-6));
        }
    CHECK(worst < 1e-5);
    CHECK(worst_linear > 1e-2);  // the axis matters: the same factors on the linear axis differ
}

TEST_CASE("factored: factors on a warped θd axis round-trip through .brdfz with their axis",
          "[factored][container][warp]") {
    test::TempDir dir;
    const std::string path = (dir.path / "w.brdfz").string();
    const Factored f = factor(coated({12, 10, 20, BinPosition::Centre, 0.65}),
                              options(FactorMethod::Svd, 3, FactorSpace::Cos, FactorLayout::HxDP, FactorColour::Shared));
    const container::Achieved a = container::write(path, *f.brdf);
    CHECK(a.lossless);
    CHECK(a.nbytes == f.brdf->nbytes());
    const container::ReadResult r = container::read(path);
    CHECK(r.meta.features ==
          std::vector<container::Feature>{{"core", 1}, {"factored", 2}, {"factored.warped-theta-d", 2}});
    const auto* back = dynamic_cast<const FactoredBrdf*>(r.brdf.get());
    REQUIRE(back);
    CHECK(back->factors().grid == f.brdf->factors().grid);  // the warp included
    CHECK(back->factors().u == f.brdf->factors().u);
    CHECK(back->factors().v == f.brdf->factors().v);
    std::mt19937_64 rng(3);
    for (int k = 0; k < 200; ++k) {
        Vec3 wi = random_direction(rng), wo = random_direction(rng);
        wi.z = std::fabs(wi.z), wo.z = std::fabs(wo.z);
        const Rgb ea = f.brdf->eval(wi, wo), eb = back->eval(wi, wo);
        REQUIRE(std::memcmp(&ea, &eb, sizeof ea) == 0);
    }
}

TEST_CASE("factored: nbytes counts the float32 factors exactly", "[factored]") {
    const GridSpec g{10, 12, 24};
    const Table t = coated(g);
    const Factored sep = factor(t, options(FactorMethod::Svd, 4));
    CHECK(sep.brdf->nbytes() == 4 * 3 * 4 * (10 + 12 * 24));
    const Factored shared = factor(t, options(FactorMethod::Nmf, 4, FactorSpace::Log, FactorLayout::HDxP, FactorColour::Shared));
    CHECK(shared.brdf->nbytes() == 4 * (4 * (10 * 12 + 24) + 3 * 4));
    CHECK_THAT(shared.brdf->describe(), Catch::Contains("nmf rank 4") && Catch::Contains("float32"));
}

TEST_CASE("factored: bad input is refused with a clear error", "[factored][errors]") {
    const GridSpec g{6, 6, 12};
    const Table t = coated(g);
    CHECK_THROWS_WITH(factor(t, options(FactorMethod::Svd, 7)), Catch::Contains("rank 7 outside 1..6"));
    CHECK_THROWS_AS(factor(t, options(FactorMethod::Nmf, 0)), ValueError);
    CHECK_THROWS_WITH(factor(Table(g), options(FactorMethod::Svd, 2)), Catch::Contains("no valid bins"));
    FactorOptions o = options(FactorMethod::Svd, 2);
    o.max_iterations = 0;
    CHECK_THROWS_AS(factor(t, o), ValueError);

    Factors bad = factor(t, options(FactorMethod::Svd, 2)).brdf->factors();
    bad.u[3] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(FactoredBrdf(bad), Catch::Contains("not finite"));
    bad = factor(t, options(FactorMethod::Svd, 2)).brdf->factors();
    bad.v.pop_back();
    CHECK_THROWS_AS(FactoredBrdf(bad), ValueError);
    bad = factor(t, options(FactorMethod::Svd, 2)).brdf->factors();
    bad.max_value[1] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(FactoredBrdf(bad), Catch::Contains("max_value"));
    bad.max_value[1] = -1.0f;
    CHECK_THROWS_WITH(FactoredBrdf(bad), Catch::Contains("max_value"));

    CHECK_THROWS_WITH(parse_factor_space("sqrt"), Catch::Contains("linear, cos, log, cbrt"));
}

TEST_CASE("factored: progress is reported and the iteration cap is honoured", "[factored]") {
    const Table t = coated({12, 12, 24});
    FactorOptions o = options(FactorMethod::Nmf, 3, FactorSpace::Log);
    o.max_iterations = 5;
    o.tolerance = 0;  // never converged: runs to the cap
    std::vector<double> seen;
    o.progress = [&](double p) { seen.push_back(p); };
    const Factored f = factor(t, o);
    CHECK(f.report.iterations == 5);
    CHECK_FALSE(f.report.converged);
    REQUIRE(seen.size() == 15);  // 5 iterations x 3 channels
    CHECK(std::is_sorted(seen.begin(), seen.end()));
    CHECK(seen.back() == Approx(1.0));
}

TEST_CASE("factored: compress kinds svd and nmf", "[factored][compress]") {
    const TabularBrdf source(coated({16, 16, 32}));
    const Compressed a = compress(source, "svd:rank=4,space=log");
    const auto* fa = dynamic_cast<const FactoredBrdf*>(a.brdf.get());
    REQUIRE(fa);
    CHECK(fa->factors().rank == 4);
    CHECK(fa->factors().space == FactorSpace::Log);
    CHECK(fa->factors().grid == source.table().grid());  // a table source is factored on its own grid
    CHECK(a.spec == "svd:rank=4,space=log");

    const Compressed b = compress(source, "nmf:rank=3");
    const auto* fb = dynamic_cast<const FactoredBrdf*>(b.brdf.get());
    REQUIRE(fb);
    CHECK(fb->factors().method == FactorMethod::Nmf);
    CHECK(fb->factors().rank == 3);

    const Compressed c = compress(source, "nmf:rank=2,space=cbrt,layout=hd_p,colour=shared,res=8x8x16");
    const auto* fc = dynamic_cast<const FactoredBrdf*>(c.brdf.get());
    REQUIRE(fc);
    CHECK(fc->factors().grid.str() == "8x8x16");
    CHECK(fc->factors().layout == FactorLayout::HDxP);
    CHECK(fc->factors().colour == FactorColour::Shared);
    CHECK(c.brdf->nbytes() == 4 * (2 * (64 + 16) + 6));

    // dwarp=W: the res= grid on the warped θd axis (table.h), the size unchanged.
    const Compressed d = compress(source, "svd:rank=2,space=cos,colour=shared,res=8x8x16,dwarp=0.8");
    const auto* fd = dynamic_cast<const FactoredBrdf*>(d.brdf.get());
    REQUIRE(fd);
    CHECK(fd->factors().grid == GridSpec{8, 8, 16, BinPosition::Centre, 0.8});
    CHECK_THAT(d.brdf->describe(), Catch::Contains("(bin centre, theta_d warp 0.8)"));
    CHECK(d.brdf->nbytes() == 4 * (2 * (8 + 8 * 16) + 6));
    CHECK_THROWS_WITH(compress(source, "svd:rank=2,dwarp=0.8"), Catch::Contains("dwarp= applies to the res= grid"));
    CHECK_THROWS_WITH(compress(source, "nmf:rank=2,res=8x8x16,dwarp=0.99"), Catch::Contains("dwarp=0.99 is outside"));

    CHECK_THROWS_WITH(compress(source, "svd:rank=0"), Catch::Contains("rank"));
    CHECK_THROWS_WITH(compress(source, "svd:space=sqrt"), Catch::Contains("space"));
    CHECK_THROWS_WITH(compress(source, "nmf:rnak=3"), Catch::Contains("rnak"));
    CHECK_THROWS_WITH(compress(source, "svd:rank=40"), Catch::Contains("rank 40 outside"));
}

TEST_CASE("factored: .brdfz round trip is bit for bit", "[factored][container]") {
    test::TempDir dir;
    const std::string path = (dir.path / "f.brdfz").string();
    const Table t = coated({12, 10, 20});
    std::mt19937_64 rng(2);
    for (FactorColour colour : {FactorColour::Separate, FactorColour::Shared})
        for (FactorLayout layout : {FactorLayout::HxDP, FactorLayout::HDxP}) {
            const Factored f = factor(t, options(FactorMethod::Svd, 3, FactorSpace::Log, layout, colour));
            const container::Achieved a = container::write(path, *f.brdf);
            CHECK(a.lossless);
            CHECK(a.nbytes == f.brdf->nbytes());
            const container::ReadResult r = container::read(path);
            CHECK(r.meta.representation == "factored");
            CHECK(r.meta.features == std::vector<container::Feature>{{"core", 1}, {"factored", 2}});
            CHECK(r.meta.min_reader_version == 2);
            const auto* back = dynamic_cast<const FactoredBrdf*>(r.brdf.get());
            REQUIRE(back);
            const Factors &x = f.brdf->factors(), &y = back->factors();
            CHECK(std::memcmp(x.u.data(), y.u.data(), x.u.size() * 4) == 0);
            CHECK(x.u.size() == y.u.size());
            CHECK(x.v == y.v);
            CHECK(x.colour_weights == y.colour_weights);
            CHECK(x.max_value == y.max_value);
            CHECK(back->describe() == f.brdf->describe());
            for (int k = 0; k < 200; ++k) {
                Vec3 wi = random_direction(rng), wo = random_direction(rng);
                wi.z = std::fabs(wi.z), wo.z = std::fabs(wo.z);
                const Rgb ea = f.brdf->eval(wi, wo), eb = back->eval(wi, wo);
                REQUIRE(std::memcmp(&ea, &eb, sizeof ea) == 0);
            }
        }
}

namespace {

const double kThetaODeg[] = {0, 30, 60, 80, 87};

}  // namespace

TEST_CASE("factored sampler: chi-square, normalisation, round trip", "[factored][sample][heavy]") {
    const Table t = coated({45, 45, 90}, 0.08);
    for (FactorMethod method : {FactorMethod::Svd, FactorMethod::Nmf}) {
        const Factored f = factor(t, options(method, 3, FactorSpace::Log));
        const Brdf& b = *f.brdf;
        const double alpha = 0.01 / std::size(kThetaODeg);  // Bonferroni-corrected 1% level
        for (double deg : kThetaODeg) {
            INFO(factor_method_name(method) << " theta_o = " << deg);
            const Vec3 wo = spherical_direction(deg * M_PI / 180, 0.4);
            CHECK(test::chi2_test(b, wo, 1000000, 32, 1, test::Draws::Batch).p_value > alpha);
            CHECK(test::pdf_integral(b, wo) == Approx(1.0).margin(0.01));
            std::mt19937_64 rng(7);
            std::uniform_real_distribution<double> u(0, 1);
            for (int k = 0; k < 1000; ++k) {
                const BrdfSample s = b.sample(wo, u(rng), u(rng));
                if (s.pdf == 0) continue;
                REQUIRE(s.pdf == Approx(b.pdf(wo, s.wi)).epsilon(1e-9));
                const Rgb e = b.eval(s.wi, wo);
                REQUIRE(s.weight[0] == Approx(e[0] * s.wi.z / s.pdf).epsilon(1e-9));
            }
        }
    }
}

namespace {

// n random (wo, u): finite, non-negative pdfs and weights, few draws lost.
void check_random_draws(std::size_t n) {
    const Factored f = factor(coated({32, 32, 64}, 0.05), options(FactorMethod::Svd, 2, FactorSpace::Linear));
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    std::size_t bad = 0, failed = 0;
    for (std::size_t k = 0; k < n; ++k) {
        Vec3 wo = random_direction(rng);
        wo.z = std::fabs(wo.z);
        const BrdfSample s = f.brdf->sample(wo, u(rng), u(rng));
        failed += s.pdf == 0;
        bad += !(std::isfinite(s.pdf) && s.pdf >= 0 && std::isfinite(s.weight[0]) && std::isfinite(s.weight[1]) &&
                 std::isfinite(s.weight[2]) && s.weight[0] >= 0 && s.weight[1] >= 0 && s.weight[2] >= 0);
    }
    CHECK(bad == 0);
    CHECK(failed < n / 50);
}

}  // namespace

TEST_CASE("factored sampler: 10^7 random (wo, u) give finite, non-negative pdfs and weights",
          "[factored][sample][heavy]") {
    check_random_draws(10000000);
}

// The sanitizers' share of the test above (the same draws, first 10^5).
TEST_CASE("factored sampler: 10^5 random (wo, u) give finite, non-negative pdfs and weights",
          "[factored][sample][light]") {
    check_random_draws(100000);
}

TEST_CASE("factored: real MERL tables", "[factored][data][heavy]") {
    const auto files = test::merl_tables();
    if (files.empty()) {
        WARN("skipped: no MERL tables (../shared missing, or numpy unavailable to generate them)");
        return;
    }
    for (const auto& path : files) {
        INFO(path);
        const Loaded l = load(path.string());
        const auto* source = dynamic_cast<const TabularBrdf*>(l.brdf.get());
        REQUIRE(source);
        // Factored on the full grid in log space: the residual falls with rank; every output finite.
        double previous = std::numeric_limits<double>::infinity();
        for (int rank : {1, 2, 4}) {
            FactorOptions o = options(FactorMethod::Svd, rank, FactorSpace::Log);
            o.max_iterations = 20;
            const Factored f = factor(source->table(), o);
            const Metrics m = compare(*source, *f.brdf);
            INFO("rank " << rank << " residual " << f.report.residual << " cos_rmse_rel " << m.cos_rmse_rel.mean);
            CHECK(f.report.residual < previous);
            CHECK(std::isfinite(m.cos_rmse_rel.mean));
            previous = f.report.residual;
        }
        const Compressed n = compress(*source, "nmf:rank=3,colour=shared,iterations=30");
        const Metrics m = compare(*source, *n.brdf);
        INFO("nmf:rank=3,colour=shared cos_rmse_rel " << m.cos_rmse_rel.mean);
        CHECK(m.cos_rmse_rel.mean < 0.5);
        CHECK(dynamic_cast<const FactoredBrdf&>(*n.brdf).clamped_evaluations() == 0);
    }
}
