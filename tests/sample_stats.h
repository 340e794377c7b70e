// Statistical checks of samplers (as pbrt's and Mitsuba's tests do): a χ² goodness-of-fit test of
// sampled directions against the pdf, and the integral of the pdf over the hemisphere.
// Both work in half-vector coordinates relative to wo — y = √(θh/(π/2)), x = (φh − φo)/2π + ½ — where
// specular peaks are wide, and integrate the pdf with the Jacobian dωi = 4 (wo·h) · π y sinθh · 2π dx dy.
#pragma once

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <random>
#include <utility>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/coords.h"
#include "simd_levels.h"

namespace brdfz::test {

struct HalfCoords {
    double x, y;
};

inline HalfCoords half_coords(const Vec3& wo, const Vec3& wi) {
    const Vec3 h = half_vector(wi, wo);
    const double phi_o = std::atan2(wo.y, wo.x);
    double x = (std::atan2(h.y, h.x) - phi_o) / (2 * M_PI) + 0.5;
    x -= std::floor(x);
    return {x, std::sqrt(elevation(h) / (M_PI / 2))};
}

// wi for half-vector coordinates, and the Jacobian dωi / dx dy (0 where wi is below the horizon).
inline Vec3 wi_at(const Vec3& wo, double x, double y, double* jacobian) {
    const double phi_o = std::atan2(wo.y, wo.x), theta_h = M_PI / 2 * y * y;
    const Vec3 h = spherical_direction(theta_h, phi_o + (x - 0.5) * 2 * M_PI);
    const Vec3 wi = (2 * dot(wo, h)) * h - wo;
    *jacobian = wi.z > 0 ? 4 * dot(wo, h) * M_PI * y * std::sin(theta_h) * 2 * M_PI : 0.0;
    return wi;
}

// Points of a quadrature rule in half-vector coordinates whose pdf goes through the batch pdf, which
// gives one call's bits (check_batch_sampler); the sums run in the points' order, as one call at a
// time would.
class PdfRule {
public:
    explicit PdfRule(const Vec3& wo) : wo_(wo) {}
    void add(double x, double y) {
        double jac;
        wi_.push_back(wi_at(wo_, x, y, &jac));
        jacobian_.push_back(jac);
    }
    // sum plus pdf(wo, wi)·jacobian at each point added since the last call, where the jacobian is > 0.
    double accumulate(const Brdf& b, double sum) {
        views_.resize(wi_.size(), wo_);
        pdf_.resize(wi_.size());
        b.pdf(std::span<const Vec3>(views_.data(), wi_.size()), std::span<const Vec3>(wi_), std::span(pdf_));
        for (std::size_t k = 0; k < wi_.size(); ++k)
            if (jacobian_[k] > 0) sum += pdf_[k] * jacobian_[k];
        wi_.clear(), jacobian_.clear();
        return sum;
    }

private:
    Vec3 wo_;
    std::vector<Vec3> views_, wi_;
    std::vector<double> jacobian_, pdf_;
};

// ∫ pdf(wo, wi) dωi over the upper hemisphere, by a midpoint rule with n×n points per unit square.
inline double pdf_integral(const Brdf& b, const Vec3& wo, int n = 1024) {
    double sum = 0;
    PdfRule rule(wo);
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) rule.add((i + 0.5) / n, (j + 0.5) / n);
        sum = rule.accumulate(b, sum);
    }
    return sum / (double(n) * n);
}

// Regularised upper incomplete gamma Q(a, x): series below a + 1, continued fraction above.
inline double gamma_q(double a, double x) {
    if (x <= 0) return 1.0;
    const double lg = std::lgamma(a);
    if (x < a + 1) {
        double sum = 1.0 / a, term = sum;
        for (int n = 1; n < 1000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::fabs(term) < std::fabs(sum) * 1e-15) break;
        }
        return 1.0 - sum * std::exp(-x + a * std::log(x) - lg);
    }
    double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;  // modified Lentz
    for (int i = 1; i < 1000; ++i) {
        const double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (std::fabs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        const double del = d * c;
        h *= del;
        if (std::fabs(del - 1) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - lg) * h;
}

struct Chi2Result {
    double p_value;
    int dof;
    std::size_t failed;  // samples with pdf 0
    double integral;     // ∫ pdf dωi over the hemisphere, from the expected counts' quadrature
};

// How chi2_test draws: one sample() call per draw, or the batch sample() over spans of draws.
enum class Draws { OneAtATime, Batch };

// Quadrature points a side per χ² cell. The compact sampler's density is piecewise constant on cells
// whose edges cross the χ² cells' (rows on its own θh edges, columns scaled by the azimuth the horizon
// leaves): on 16×16 points that quadrature's error alone failed the test at 3·10^6 draws, so its
// samplers (every gridded kind's default) take 32. Samplers whose density is smooth across the cells
// (the analytic lobes, RGL files' warps, the factor and half-vector samplers) take 16, a quarter of the
// pdf calls.
inline constexpr int kCompactPoints = 32, kSmoothPoints = 16;

// Histogram of `samples` sampled wi against expected counts from the pdf on a cells×cells grid in
// half-vector coordinates; cells with expected count < 5 are pooled. The expected counts' quadrature
// (cells·points a side, twice that where the horizon crosses) also gives the pdf's integral.
inline Chi2Result chi2_test(const Brdf& b, const Vec3& wo, std::size_t samples, int cells = 32,
                            std::uint64_t seed = 1, Draws draws = Draws::OneAtATime, int points = kCompactPoints) {
    std::vector<double> observed(cells * cells, 0.0), expected(cells * cells, 0.0);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::size_t failed = 0;
    const auto count = [&](const BrdfSample& s) {
        if (s.pdf == 0) {
            ++failed;
            return;
        }
        const HalfCoords c = half_coords(wo, s.wi);
        const int i = std::min(int(c.x * cells), cells - 1), j = std::min(int(c.y * cells), cells - 1);
        observed[j * cells + i] += 1;
    };
    if (draws == Draws::Batch) {
        constexpr std::size_t kChunk = 4096;
        const std::vector<Vec3> views(kChunk, wo);
        std::vector<std::array<double, 2>> us(kChunk);
        std::vector<BrdfSample> out(kChunk);
        for (std::size_t start = 0; start < samples; start += kChunk) {
            const std::size_t m = std::min(kChunk, samples - start);
            for (std::size_t k = 0; k < m; ++k) {
                const double u1 = u(rng);
                us[k] = {u1, u(rng)};
            }
            b.sample(std::span(views.data(), m), std::span<const std::array<double, 2>>(us.data(), m), std::span(out.data(), m));
            for (std::size_t k = 0; k < m; ++k) count(out[k]);
        }
    } else {
        for (std::size_t k = 0; k < samples; ++k) count(b.sample(wo, u(rng), u(rng)));
    }
    // Expected counts by a midpoint rule on points×points per cell (kCompactPoints, kSmoothPoints).
    // Cells the horizon crosses (wi.z = 0, where the pdf may drop to 0) take twice the points a side;
    // the crossing is found on the cell's outline, which the horizon curve must cut to enter the cell.
    PdfRule rule(wo);
    const auto cell_integral = [&](int i, int j, int sub) {
        for (int a = 0; a < sub; ++a)
            for (int c = 0; c < sub; ++c) rule.add((i + (a + 0.5) / sub) / cells, (j + (c + 0.5) / sub) / cells);
        return rule.accumulate(b, 0.0) / (sub * sub);
    };
    const auto horizon_crosses = [&](int i, int j) {
        constexpr int kProbes = 128;
        int above = 0;
        for (int e = 0; e < 4 * kProbes; ++e) {
            const int edge = e / kProbes;
            const double t = double(e % kProbes) / kProbes;
            const double cx = edge == 0 ? t : edge == 1 ? 1 : edge == 2 ? 1 - t : 0;
            const double cy = edge == 0 ? 0 : edge == 1 ? t : edge == 2 ? 1 : 1 - t;
            double jac;
            wi_at(wo, std::fmin((i + cx) / cells, 1.0), std::fmin((j + cy) / cells, 1.0), &jac);
            above += jac > 0;
        }
        return above > 0 && above < 4 * kProbes;
    };
    double integral = 0;
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const double mass = cell_integral(i, j, horizon_crosses(i, j) ? 2 * points : points) / (double(cells) * cells);
            integral += mass;
            expected[j * cells + i] = mass * samples;
        }
    double chi2 = 0, pooled_o = 0, pooled_e = 0;
    int dof = -1;
    for (std::size_t k = 0; k < expected.size(); ++k) {
        if (expected[k] < 5) {
            pooled_o += observed[k];
            pooled_e += expected[k];
            continue;
        }
        chi2 += (observed[k] - expected[k]) * (observed[k] - expected[k]) / expected[k];
        ++dof;
    }
    if (pooled_e >= 5) {
        chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        ++dof;
    }
    return {dof > 0 ? gamma_q(dof / 2.0, chi2 / 2.0) : 0.0, dof, failed, integral};
}

// The view elevations the issue asks every sampler to be tested at.
inline constexpr double kThetaODeg[] = {0, 30, 60, 80, 87};

// The 1 % level, Bonferroni-corrected over the five views: check_sampler's default.
inline constexpr double kViewsLevel = 0.01 / std::size(kThetaODeg);

// How check_sampler's χ² draws (one call at a time or through the batch sampler, whose draws
// check_batch_bits shows are one call's bits) and on how many cells a side: the expected counts'
// quadrature takes cells·points a side, so 16 cells cost a quarter of 32's (for few draws).
struct Chi2Setting {
    Draws draws = Draws::OneAtATime;
    int cells = 32;
    int points = kCompactPoints;
};

// At each of kThetaODeg: χ² of `samples` draws against the pdf (fails below p_min: callers Bonferroni-
// correct it for the number of tests they run), ∫ pdf dωi = the share of draws that succeed ± 1% (on the
// χ² test's quadrature),
// and the sample → pdf round trip with the weight f·cosθi/pdf.
inline void check_sampler(const Brdf& b, std::size_t samples, double p_min = kViewsLevel, Chi2Setting chi2 = {}) {
    for (double deg : kThetaODeg) {
        INFO("theta_o = " << deg);
        const Vec3 wo = spherical_direction(deg * M_PI / 180, 0.4);
        const Chi2Result r = chi2_test(b, wo, samples, chi2.cells, 1, chi2.draws, chi2.points);
        CHECK(r.p_value > p_min);
        // The probability that a draw succeeds: 1 for most samplers; an RGL file's reflects about microfacet
        // normals, some of which send it below the horizon (formats/include/brdfz/formats/rgl.h).
        CHECK(r.integral == Approx(1.0 - static_cast<double>(r.failed) / static_cast<double>(samples)).margin(0.01));
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> u(0, 1);
        for (int k = 0; k < 1000; ++k) {
            const BrdfSample s = b.sample(wo, u(rng), u(rng));
            if (s.pdf == 0) continue;
            REQUIRE(s.pdf == Approx(b.pdf(wo, s.wi)).epsilon(1e-9));
            const Rgb f = b.eval(s.wi, wo);
            for (int c = 0; c < 3; ++c) REQUIRE(s.weight[c] == Approx(f[c] * s.wi.z / s.pdf).epsilon(1e-9));
        }
    }
}

// The batch sampler (sample() over spans): χ² of `samples` batch draws at each of kThetaODeg (fails below
// p_min), and check_batch_bits.
inline void check_batch_sampler(const Brdf& b, std::size_t samples, double p_min = kViewsLevel);
// At every SIMD build the CPU has, batch sample, pdf and eval equal to one call at a time, bit for bit,
// on 3,000 random views and pairs (views and wi above and below the horizon, u in and out of [0, 1)),
// and most draws succeed.
inline void check_batch_bits(const Brdf& b);

// count random views above the horizon and u pairs, from one seeded generator.
inline std::pair<std::vector<Vec3>, std::vector<std::array<double, 2>>> random_views(std::size_t count,
                                                                                     std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    std::normal_distribution<double> nd;
    std::vector<Vec3> wo(count);
    std::vector<std::array<double, 2>> us(count);
    for (std::size_t k = 0; k < count; ++k) {
        wo[k] = normalize({nd(rng), nd(rng), nd(rng)});
        wo[k].z = std::fabs(wo[k].z);
        us[k] = {u(rng), u(rng)};
    }
    return {wo, us};
}

inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
inline bool same_bits(const Rgb& a, const Rgb& b) {
    return same_bits(a[0], b[0]) && same_bits(a[1], b[1]) && same_bits(a[2], b[2]);
}
inline bool same_bits(const BrdfSample& a, const BrdfSample& b) {
    return same_bits(a.wi.x, b.wi.x) && same_bits(a.wi.y, b.wi.y) && same_bits(a.wi.z, b.wi.z) &&
           same_bits(a.pdf, b.pdf) && same_bits(a.weight, b.weight);
}

inline void check_batch_sampler(const Brdf& b, std::size_t samples, double p_min) {
    for (double deg : kThetaODeg) {
        INFO("batch draws, theta_o = " << deg);
        CHECK(chi2_test(b, spherical_direction(deg * M_PI / 180, 0.4), samples, 32, 3, Draws::Batch).p_value > p_min);
    }
    check_batch_bits(b);
}

inline void check_batch_bits(const Brdf& b) {
    // Views above and below the horizon, u in and out of [0, 1).
    auto [wo, u] = random_views(3000, 21);
    for (std::size_t k = 0; k < wo.size(); k += 97) wo[k].z = -wo[k].z;
    for (std::size_t k = 5; k < u.size(); k += 89) u[k][k % 2] = k % 3 ? 1.0 : -0.25;
    auto [wi, unused] = random_views(wo.size(), 22);
    for (std::size_t k = 0; k < wi.size(); k += 13) wi[k].z = -wi[k].z;
    std::vector<BrdfSample> s(wo.size());
    std::vector<double> p(wo.size());
    std::vector<Rgb> f(wo.size());
    for (detail::Simd level : simd_levels()) {
        INFO(simd_label(level) << " build");
        const SimdCap cap(level);
        b.sample(std::span<const Vec3>(wo), std::span<const std::array<double, 2>>(u), std::span(s));
        b.pdf(std::span<const Vec3>(wo), std::span<const Vec3>(wi), std::span(p));
        b.eval(std::span<const Vec3>(wi), std::span<const Vec3>(wo), std::span(f));
        std::size_t differ = 0, drawn = 0;
        for (std::size_t k = 0; k < wo.size(); ++k) {
            differ += !same_bits(s[k], b.sample(wo[k], u[k][0], u[k][1]));
            differ += !same_bits(p[k], b.pdf(wo[k], wi[k]));
            differ += !same_bits(f[k], b.eval(wi[k], wo[k]));
            drawn += s[k].pdf > 0;
        }
        CHECK(differ == 0);
        CHECK(drawn > wo.size() / 2);
    }
}

}  // namespace brdfz::test
