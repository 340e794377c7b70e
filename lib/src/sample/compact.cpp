#include "brdfz/sample/compact.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string>

#include "brdfz/errors.h"
#include "brdfz/repr/compact_table.h"
#include "detail/parallel.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;
namespace rk = runtime::kernels;

// s = sin²(θh/2) at y = √(θh/(π/2)), MERL's θh axis.
double s_at(double y) {
    const double half = std::sin(y * y * (kPi / 4.0));
    return half * half;
}

// Sums of g over point sets ("bins"), each point one direction pair of a slice: points are added with
// the bin they count for, then evaluated in one batch.
class Integrand {
public:
    Integrand(const Brdf& brdf, double theta_o, int azimuths)
        : brdf_(brdf), sin_o_(std::sin(theta_o)), cos_o_(std::cos(theta_o)) {
        for (int a = 0; a < azimuths; ++a) views_.push_back(spherical_direction(theta_o, 2.0 * kPi * a / azimuths));
    }

    // The kernel's φmax at s for this slice's view.
    double valid_azimuth(double s) const { return rk::valid_azimuth(s, sin_o_, cos_o_); }

    // The half vector at (s, φ) on one side of each view's plane, reflected for every view azimuth.
    // `weight` multiplies the point's g (the φ-width it stands for).
    void add(std::size_t bin, double s, double phi, double side, double weight = 1.0) {
        const double sin_h = 2.0 * std::sqrt(s * (1.0 - s)), cos_h = 1.0 - 2.0 * s;
        for (const Vec3& wo : views_) {
            const double c = wo.x, sn = wo.y, r = std::sqrt(c * c + sn * sn);
            const double ca = r > 0.0 ? c / r : 1.0, sa = r > 0.0 ? sn / r : 0.0;
            const double hx = sin_h * std::cos(phi), hy = side * sin_h * std::sin(phi);
            const Vec3 h{ca * hx - sa * hy, sa * hx + ca * hy, cos_h};
            const double d = dot(wo, h);
            wi_.push_back((2.0 * d) * h - wo);
            wo_.push_back(wo);
            jacobian_.push_back(4.0 * d);
            weight_.push_back(weight);
            bin_.push_back(bin);
        }
    }

    // Adds each point's g to its bin's sum and forgets the points.
    void accumulate(std::vector<double>& sums) {
        f_.resize(wi_.size());
        brdf_.eval(std::span<const Vec3>(wi_), std::span<const Vec3>(wo_), std::span<Rgb>(f_));
        for (std::size_t k = 0; k < wi_.size(); ++k) {
            const double y = 0.2126 * f_[k][0] + 0.7152 * f_[k][1] + 0.0722 * f_[k][2];
            const double g = y * wi_[k].z * jacobian_[k] * weight_[k];
            // Non-finite or negative data gets no importance; the cosine share still covers it.
            if (wi_[k].z > 0.0 && jacobian_[k] > 0.0 && std::isfinite(g) && g > 0.0) sums[bin_[k]] += g;
        }
        wi_.clear(), wo_.clear(), jacobian_.clear(), weight_.clear(), bin_.clear();
    }

private:
    const Brdf& brdf_;
    double sin_o_, cos_o_;
    std::vector<Vec3> views_, wi_, wo_;
    std::vector<double> jacobian_, weight_;
    std::vector<std::size_t> bin_;
    std::vector<Rgb> f_;
};

// Upper ends of the intervals of `mass` (non-negative) in units of full/total, the last one `full`;
// an all-zero (or non-finite) mass gets `fallback`'s proportions.
template <typename T>
void fixed_point_cdf(std::span<const double> mass, std::span<const double> fallback, double full, T* ends) {
    double total = 0.0;
    for (double m : mass) total += m;
    const bool use = total > 0.0 && std::isfinite(total);
    const std::span<const double> w = use ? mass : fallback;
    if (!use) {
        total = 0.0;
        for (double m : w) total += m;
    }
    double sum = 0.0;
    for (std::size_t i = 0; i < w.size(); ++i) {
        sum += w[i];
        ends[i] = static_cast<T>(std::min(std::nearbyint(sum / total * full), full));
    }
    ends[w.size() - 1] = static_cast<T>(full);
}

void check_tables(const CompactSampler::Tables& t) {
    const auto fail = [](const std::string& why) { throw ValueError("compact sampler: " + why); };
    if (t.slices < 2 || t.slices > 1024 || t.rows < 1 || t.rows > 4096 || t.cols < 1 || t.cols > 4096)
        fail("slices, rows or cols out of range (2-1024, 1-4096, 1-4096)");
    const std::size_t rows = static_cast<std::size_t>(t.slices) * t.rows;
    if (t.s_edges.size() != static_cast<std::size_t>(t.rows) + 1 || t.row_cdf.size() != rows ||
        t.col_cdf.size() != rows * t.cols || t.edge_weight.size() != static_cast<std::size_t>(t.slices) * (t.rows + 1))
        fail("table sizes do not match slices, rows and cols");
    const rk::CompactSamplerView v{t.slices,         t.rows,           t.cols,           t.cos_theta_max,
                                   t.cosine_share,   t.s_edges.data(), t.row_cdf.data(), t.col_cdf.data(),
                                   t.edge_weight.data()};
    if (const char* why = rk::check_compact_sampler(v)) fail(why);
}

}  // namespace

CompactSampler::CompactSampler(const Brdf& brdf, const CompactSamplerOptions& o) {
    if (o.slices < 2 || o.slices > 1024 || o.rows < 1 || o.rows > 4096 || o.cols < 1 || o.cols > 4096)
        throw ValueError("compact sampler: slices, rows or cols out of range (2-1024, 1-4096, 1-4096)");
    if (!(o.cosine_share > 0.0 && o.cosine_share < 1.0))
        throw ValueError("compact sampler: cosine_share must be in (0, 1)");
    if (!(o.uniform_share >= 0.0 && o.uniform_share <= 1.0))
        throw ValueError("compact sampler: uniform_share must be in [0, 1]");
    if (o.points < 1 || o.points > 8 || o.view_azimuths < 1 || o.view_azimuths > 64)
        throw ValueError("compact sampler: points (1-8) or view_azimuths (1-64) out of range");
    const int K = o.slices, R = o.rows, C = o.cols, P = o.points;
    t_.slices = K, t_.rows = R, t_.cols = C;
    t_.cos_theta_max = std::cos(kMaxThetaODeg * kPi / 180.0);
    t_.cosine_share = o.cosine_share;
    const auto theta_o = [&](int k) { return std::acos(1.0 - (1.0 - t_.cos_theta_max) * k / (K - 1)); };

    // Row placement: g's θh marginal on fine rows uniform in y, per slice.
    constexpr int kFinePerRow = 8, kFinePhi = 8;
    const int F = kFinePerRow * R;
    std::vector<double> fine(static_cast<std::size_t>(K) * F, 0.0);
    detail::parallel_for(K, o.threads, [&](int, int k) {
        Integrand g(brdf, theta_o(k), o.view_azimuths);
        std::vector<double> sums(F, 0.0);
        for (int i = 0; i < F; ++i) {
            const double s0 = s_at(static_cast<double>(i) / F), s1 = s_at(static_cast<double>(i + 1) / F);
            const double s = 0.5 * (s0 + s1), phi_max = g.valid_azimuth(s);
            for (int j = 0; j < kFinePhi; ++j) g.add(i, s, (j + 0.5) * phi_max / kFinePhi, 1.0, phi_max);
        }
        g.accumulate(sums);
        for (int i = 0; i < F; ++i) {
            const double ds = s_at(static_cast<double>(i + 1) / F) - s_at(static_cast<double>(i) / F);
            fine[static_cast<std::size_t>(k) * F + i] = sums[i] * ds;  // ∝ g's integral over the fine row
        }
    });
    std::vector<double> mix(F, 0.0);
    int counted = 0;
    for (int k = 0; k < K; ++k) {
        const double* m = &fine[static_cast<std::size_t>(k) * F];
        double total = 0.0;
        for (int i = 0; i < F; ++i) total += m[i];
        if (!(total > 0.0 && std::isfinite(total))) continue;
        ++counted;
        for (int i = 0; i < F; ++i) mix[i] += m[i] / total;
    }
    const double data_share = counted > 0 ? 1.0 - o.uniform_share : 0.0;
    for (int i = 0; i < F; ++i) mix[i] = (counted > 0 ? data_share * mix[i] / counted : 0.0) + (1.0 - data_share) / F;
    std::vector<double> cdf(F + 1, 0.0);
    for (int i = 0; i < F; ++i) cdf[i + 1] = cdf[i] + mix[i];
    t_.s_edges.assign(R + 1, 0.0f);
    for (int r = 1; r < R; ++r) {
        const double target = cdf[F] * r / R;
        const int i = std::clamp(static_cast<int>(std::upper_bound(cdf.begin(), cdf.end(), target) - cdf.begin()) - 1, 0, F - 1);
        const double frac = cdf[i + 1] > cdf[i] ? (target - cdf[i]) / (cdf[i + 1] - cdf[i]) : 0.0;
        t_.s_edges[r] = static_cast<float>(s_at((i + std::clamp(frac, 0.0, 1.0)) / F));
    }
    t_.s_edges[R] = 0.5f;
    // Quantiles closer than a float's step would leave an empty row.
    for (int r = 1; r <= R; ++r)
        if (!(t_.s_edges[r] > t_.s_edges[r - 1])) t_.s_edges[r] = std::nextafter(t_.s_edges[r - 1], 1.0f);
    for (int r = R - 1; r > 0 && !(t_.s_edges[r] < t_.s_edges[r + 1]); --r)
        t_.s_edges[r] = std::nextafter(t_.s_edges[r + 1], 0.0f);
    if (!(t_.s_edges[1] > 0.0f)) throw ValueError("compact sampler: more rows than the float edges can hold");

    // Edge weights: g's integral over φ at each row edge (2·cols points per side), per slice, scaled to a
    // largest weight of 1 and kept as binary16.
    t_.edge_weight.resize(static_cast<std::size_t>(K) * (R + 1));
    detail::parallel_for(K, o.threads, [&](int, int k) {
        Integrand g(brdf, theta_o(k), o.view_azimuths);
        std::vector<double> sums(R + 1, 0.0);
        for (int e = 0; e <= R; ++e) {
            const double s = t_.s_edges[e], phi_max = g.valid_azimuth(s);
            for (int j = 0; j < 2 * C; ++j)
                for (double side : {1.0, -1.0}) g.add(e, s, (j + 0.5) * phi_max / (2 * C), side, phi_max);
        }
        g.accumulate(sums);
        const double top = *std::max_element(sums.begin(), sums.end());
        for (int e = 0; e <= R; ++e)
            t_.edge_weight[static_cast<std::size_t>(k) * (R + 1) + e] =
                half_from_float(top > 0.0 && std::isfinite(top) ? static_cast<float>(sums[e] / top) : 1.0f);
    });

    // Cell masses: g over P×P points per side, each weighted by the φ-width it stands for, times the
    // row's s-width (a cell's solid angle is 4·Δs·φmax(s)/cols).
    t_.row_cdf.resize(static_cast<std::size_t>(K) * R);
    t_.col_cdf.resize(static_cast<std::size_t>(K) * R * C);
    std::vector<double> uniform_rows(R), uniform_cols(C, 1.0);
    for (int r = 0; r < R; ++r) uniform_rows[r] = static_cast<double>(t_.s_edges[r + 1]) - t_.s_edges[r];
    detail::parallel_for(K, o.threads, [&](int, int k) {
        Integrand g(brdf, theta_o(k), o.view_azimuths);
        std::vector<double> cells(static_cast<std::size_t>(R) * C, 0.0), rows(R, 0.0);
        for (int r = 0; r < R; ++r) {
            const double s0 = t_.s_edges[r], ds = static_cast<double>(t_.s_edges[r + 1]) - s0;
            for (int i = 0; i < P; ++i) {
                const double s = s0 + (i + 0.5) / P * ds, phi_max = g.valid_azimuth(s);
                for (int c = 0; c < C; ++c)
                    for (int j = 0; j < P; ++j)
                        for (double side : {1.0, -1.0})
                            g.add(static_cast<std::size_t>(r) * C + c, s, (c + (j + 0.5) / P) * phi_max / C, side,
                                  phi_max);
            }
            g.accumulate(cells);
            for (int c = 0; c < C; ++c) {
                cells[static_cast<std::size_t>(r) * C + c] *= ds;
                rows[r] += cells[static_cast<std::size_t>(r) * C + c];
            }
        }
        for (int r = 0; r < R; ++r)
            fixed_point_cdf<std::uint16_t>(std::span<const double>(&cells[static_cast<std::size_t>(r) * C], C),
                                           uniform_cols, rk::kColUnits,
                                           &t_.col_cdf[(static_cast<std::size_t>(k) * R + r) * C]);
        fixed_point_cdf<std::uint32_t>(rows, uniform_rows, rk::kRowUnits, &t_.row_cdf[static_cast<std::size_t>(k) * R]);
    });
    check_tables(t_);
}

CompactSampler::CompactSampler(Tables tables) : t_(std::move(tables)) { check_tables(t_); }

runtime::kernels::CompactSamplerView CompactSampler::view() const {
    return {t_.slices,         t_.rows,           t_.cols,           t_.cos_theta_max,     t_.cosine_share,
            t_.s_edges.data(), t_.row_cdf.data(), t_.col_cdf.data(), t_.edge_weight.data()};
}

BrdfSample CompactSampler::sample(const Vec3& wo, double u1, double u2) const {
    const rk::CompactDraw d = rk::compact_sample(view(), wo, u1, u2);
    return {d.wi, d.pdf, {}};
}

double CompactSampler::pdf(const Vec3& wo, const Vec3& wi) const { return rk::compact_pdf(view(), wo, wi); }

std::size_t CompactSampler::nbytes() const {
    return t_.s_edges.size() * sizeof(float) + t_.row_cdf.size() * sizeof(std::uint32_t) +
           (t_.col_cdf.size() + t_.edge_weight.size()) * sizeof(std::uint16_t);
}

}  // namespace brdfz
