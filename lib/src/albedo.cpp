#include "brdfz/albedo.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "brdfz/errors.h"
#include "detail/gauss_legendre.h"

namespace brdfz {
namespace {

Vec3 half_at(double theta_h, double phi_h) { return spherical_direction(theta_h, phi_h); }

Vec3 reflect(const Vec3& wo, const Vec3& h) { return (2.0 * dot(wo, h)) * h - wo; }

// Largest θh (along azimuth φh) whose mirror direction of wo stays above the horizon. wi.z > 0 at
// θh = 0; scan to the first crossing, then bisect.
double horizon_theta_h(const Vec3& wo, double phi_h) {
    constexpr int kScan = 64;
    const double top = std::numbers::pi / 2.0;
    double lo = 0.0;
    for (int s = 1; s <= kScan; ++s) {
        const double t = top * s / kScan;
        if (reflect(wo, half_at(t, phi_h)).z <= 0.0) {
            double hi = t;
            for (int it = 0; it < 60; ++it) {
                const double mid = 0.5 * (lo + hi);
                (reflect(wo, half_at(mid, phi_h)).z > 0.0 ? lo : hi) = mid;
            }
            return lo;
        }
        lo = t;
    }
    return top;
}

}  // namespace

Rgb directional_albedo(const Brdf& brdf, double theta_o, const AlbedoOptions& o) {
    if (!(theta_o >= 0.0 && theta_o < std::numbers::pi / 2.0))
        throw ValueError("albedo: theta_o must be in [0, pi/2)");
    if (o.n_phi < 1 || o.n_panels < 1 || o.order < 1 || o.order > 64)
        throw ValueError("albedo: quadrature sizes must be positive (order <= 64)");
    const Vec3 wo = spherical_direction(theta_o, 0.0);
    const detail::Quadrature gl = detail::gauss_legendre01(o.order);

    const std::size_t per_phi = static_cast<std::size_t>(o.n_panels) * o.order;
    std::vector<Vec3> wi(per_phi * o.n_phi), wos(wi.size(), wo);
    std::vector<double> weight(wi.size());
    const double dphi = 2.0 * std::numbers::pi / o.n_phi;
    for (int j = 0; j < o.n_phi; ++j) {
        const double phi_h = (j + 0.5) * dphi;
        // θh = (π/2)·u², u ∈ [0, u_max]: dθh = π u du.
        const double u_max = std::sqrt(horizon_theta_h(wo, phi_h) / (std::numbers::pi / 2.0));
        const double du = u_max / o.n_panels;
        for (int p = 0; p < o.n_panels; ++p)
            for (int q = 0; q < o.order; ++q) {
                const double u = (p + gl.x[q]) * du;
                const double theta_h = std::numbers::pi / 2.0 * u * u;
                const Vec3 h = half_at(theta_h, phi_h);
                const std::size_t k = j * per_phi + p * o.order + q;
                wi[k] = reflect(wo, h);
                // f·cosθi is applied after evaluation; here the Jacobian and quadrature weights.
                weight[k] = 4.0 * dot(wo, h) * std::sin(theta_h) * std::numbers::pi * u * gl.w[q] * du * dphi;
            }
    }
    std::vector<Rgb> f(wi.size());
    brdf.eval(wi, wos, f);
    Rgb rho{0.0, 0.0, 0.0};
    for (std::size_t k = 0; k < wi.size(); ++k)
        for (int c = 0; c < 3; ++c) rho[c] += f[k][c] * wi[k].z * weight[k];
    return rho;
}

SampledAlbedo sampled_albedo(const Brdf& brdf, double theta_o, std::size_t n, std::uint64_t seed) {
    if (!(theta_o >= 0.0 && theta_o < std::numbers::pi / 2.0))
        throw ValueError("albedo: theta_o must be in [0, pi/2)");
    if (n < 2) throw ValueError("albedo: at least 2 samples are needed");
    const Vec3 wo = spherical_direction(theta_o, 0.0);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double sum[3] = {}, sum_sq[3] = {};
    // Drawn in batches (the same draws as one call at a time), a chunk of bounded memory at a time.
    constexpr std::size_t kChunk = 4096;
    const std::size_t chunk = std::min(n, kChunk);
    const std::vector<Vec3> views(chunk, wo);
    std::vector<std::array<double, 2>> us(chunk);
    std::vector<BrdfSample> drawn(chunk);
    for (std::size_t start = 0; start < n; start += chunk) {
        const std::size_t m = std::min(chunk, n - start);
        for (std::size_t k = 0; k < m; ++k) {
            const double u1 = u(rng);
            us[k] = {u1, u(rng)};
        }
        brdf.sample(std::span(views.data(), m), std::span<const std::array<double, 2>>(us.data(), m),
                    std::span(drawn.data(), m));
        for (std::size_t k = 0; k < m; ++k)
            for (int c = 0; c < 3; ++c) {
                sum[c] += drawn[k].weight[c];
                sum_sq[c] += drawn[k].weight[c] * drawn[k].weight[c];
            }
    }
    SampledAlbedo r;
    for (int c = 0; c < 3; ++c) {
        r.mean[c] = sum[c] / n;
        const double var = std::fmax(0.0, (sum_sq[c] - n * r.mean[c] * r.mean[c]) / (n - 1));
        r.stderr_[c] = std::sqrt(var / n);
    }
    return r;
}

namespace {

constexpr double kBelowOne = 0x1.fffffffffffffp-1;  // the largest double below 1

// The luminance of sample weights, relative variance (their variance over their squared mean).
struct Moments {
    double sum = 0, sum_sq = 0;
    void add(const Rgb& w) {
        const double y = 0.2126 * w[0] + 0.7152 * w[1] + 0.0722 * w[2];
        sum += y;
        sum_sq += y * y;
    }
    double relative_variance(std::size_t n) const {
        const double mean = sum / n;
        return mean > 0.0 ? std::fmax(0.0, sum_sq / n - mean * mean) / (mean * mean) : 0.0;
    }
};

}  // namespace

double sampler_variance_ratio(const Brdf& brdf, double theta_o, std::size_t n, double floor, std::uint64_t seed) {
    if (!(theta_o >= 0.0 && theta_o < std::numbers::pi / 2.0))
        throw ValueError("albedo: theta_o must be in [0, pi/2)");
    if (n < 2) throw ValueError("albedo: at least 2 samples are needed");
    if (!(floor >= 0.0)) throw ValueError("albedo: the floor must be >= 0");
    const Vec3 wo = spherical_direction(theta_o, 0.0);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Moments own, cosine;
    for (std::size_t k = 0; k < n; ++k) {
        own.add(brdf.sample(wo, u(rng), u(rng)).weight);
        // Cosine-weighted wi: the weight f·cosθi / (cosθi/π) = π·f.
        const double u1 = u(rng), u2 = u(rng);
        const Rgb f = brdf.eval(cosine_hemisphere(u1, u2), wo);
        cosine.add({std::numbers::pi * f[0], std::numbers::pi * f[1], std::numbers::pi * f[2]});
    }
    if (!std::isfinite(own.sum_sq) || !std::isfinite(cosine.sum_sq)) return std::numeric_limits<double>::infinity();
    const double floor2 = floor * floor;
    const double mine = own.relative_variance(n) + floor2, theirs = cosine.relative_variance(n) + floor2;
    if (theirs > 0.0) return mine / theirs;
    return mine > 0.0 ? std::numeric_limits<double>::infinity() : 1.0;
}

double sampler_second_moment(const Brdf& brdf, double theta_o, std::size_t n, std::uint64_t seed) {
    if (!(theta_o >= 0.0 && theta_o < std::numbers::pi / 2.0))
        throw ValueError("albedo: theta_o must be in [0, pi/2)");
    if (n < 2) throw ValueError("albedo: at least 2 samples are needed");
    const Vec3 wo = spherical_direction(theta_o, 0.0);
    const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> jitter(0.0, 1.0);
    Moments m;
    // A row of the grid at a time, through the batch sampler (one call's draws).
    const std::vector<Vec3> views(side, wo);
    std::vector<std::array<double, 2>> us(side);
    std::vector<BrdfSample> drawn(side);
    for (std::size_t i = 0; i < side; ++i) {
        for (std::size_t j = 0; j < side; ++j)
            us[j] = {std::min((i + jitter(rng)) / side, kBelowOne), std::min((j + jitter(rng)) / side, kBelowOne)};
        brdf.sample(std::span<const Vec3>(views), std::span<const std::array<double, 2>>(us), std::span(drawn));
        for (const BrdfSample& s : drawn) m.add(s.weight);
    }
    const std::size_t count = side * side;
    if (!std::isfinite(m.sum_sq)) return std::numeric_limits<double>::infinity();
    return m.sum > 0.0 ? 1.0 + m.relative_variance(count) : 1.0;
}

}  // namespace brdfz
