#include "brdfz/sample/halfvector.h"

#include <cmath>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/azimuth.h"
#include "detail/fast_math.h"
#include "detail/grid_sweep.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;

using detail::Azimuth;
using detail::reflect;

// Half vector at cell coordinates (x, y), with φh = ±π x relative to wo.
Vec3 half_at(double x, double y, double sign) {
    return spherical_direction(kPi / 2.0 * y * y, sign * kPi * x);
}

// sin and cos over [0, π] (θh and |φh − φo|) for sample(), without libm's sincos.
const detail::SinCosTable& half_turn() {
    static const detail::SinCosTable table(kPi, 256);
    return table;
}

// wo's elevation without asin, to ~1e-10: it only places wo between two slices, and sample() and
// pdf() place it alike. sin_o = ‖wo_xy‖, which draw() also needs for wo's azimuth.
double view_elevation(double sin_o, const Vec3& wo) { return detail::fast_half_turn_angle(sin_o, wo.z); }

constexpr double kBelowOne = 0x1.fffffffffffffp-1;  // the largest double below 1

}  // namespace

HalfVectorSampler::HalfVectorSampler(const Brdf& brdf, const HalfVectorSamplerOptions& o) : options_(o) {
    if (o.n_theta_o < 2 || o.n_theta_h < 1 || o.n_phi < 1 || o.n_theta_o > 1024 || o.n_theta_h > 4096 ||
        o.n_phi > 4096)
        throw ValueError("half-vector sampler: resolutions out of range");
    if (!(o.cosine_share > 0.0 && o.cosine_share < 1.0))
        throw ValueError("half-vector sampler: cosine_share must be in (0, 1)");
    const int K = o.n_theta_o, R = o.n_theta_h, C = o.n_phi;
    theta_o_.resize(K);
    for (int k = 0; k < K; ++k) theta_o_[k] = kMaxThetaODeg * kPi / 180.0 * k / (K - 1);
    slices_.resize(K);

    // Each slice: the integrand f·cosθi·(dωi/dx dy) averaged over 2×2 points per cell.
    detail::parallel_for(K, o.threads, [&](int, int k) {
        const Vec3 wo = spherical_direction(theta_o_[k], 0.0);
        const std::size_t cells = static_cast<std::size_t>(R) * C;
        std::vector<Vec3> wi(4 * cells), wos(4 * cells, wo);
        std::vector<double> jac(4 * cells);
        for (int r = 0; r < R; ++r)
            for (int c = 0; c < C; ++c)
                for (int s = 0; s < 4; ++s) {
                    const double y = (r + 0.25 + 0.5 * (s >> 1)) / R, x = (c + 0.25 + 0.5 * (s & 1)) / C;
                    const Vec3 h = half_at(x, y, 1.0);
                    const std::size_t i = 4 * (static_cast<std::size_t>(r) * C + c) + s;
                    wi[i] = reflect(wo, h);
                    jac[i] = 4.0 * std::fmax(dot(wo, h), 0.0) * 2.0 * kPi * kPi * y * std::sin(kPi / 2.0 * y * y);
                }
        std::vector<Rgb> f(wi.size());
        brdf.eval(wi, wos, f);
        std::vector<float> weights(cells);
        for (std::size_t cell = 0; cell < cells; ++cell) {
            double sum = 0.0;
            for (int s = 0; s < 4; ++s) {
                const std::size_t i = 4 * cell + s;
                const double mean = (f[i][0] + f[i][1] + f[i][2]) / 3.0;
                // Non-finite or negative data gets no importance; the cosine share still covers it.
                if (std::isfinite(mean) && mean > 0.0 && wi[i].z > 0.0) sum += mean * wi[i].z * jac[i];
            }
            weights[cell] = std::isfinite(sum) ? static_cast<float>(sum) : 0.0f;
        }
        slices_[k] = Piecewise2D(weights, R, C);
    });
}

std::size_t HalfVectorSampler::nbytes() const {
    std::size_t n = theta_o_.size() * sizeof(double);
    for (const Piecewise2D& s : slices_) n += s.nbytes();
    return n;
}

HalfVectorSampler::SlicePair HalfVectorSampler::slices_for(double theta_o) const {
    const int K = static_cast<int>(theta_o_.size());
    // Comparisons, not std::fmin/fmax (out-of-line libm calls); NaN goes to slice 0.
    const double scaled = theta_o / theta_o_[K - 1] * (K - 1);
    const double pos = scaled > 0.0 ? (scaled < K - 1.0 ? scaled : K - 1.0) : 0.0;
    const int k0 = std::min(static_cast<int>(pos), K - 2);
    return {k0, k0 + 1, pos - k0};
}

double HalfVectorSampler::data_pdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 hw = half_vector(wi, wo);
    const Vec3 h = Azimuth(wo).to_local(hw);
    const double theta_h = elevation(h);
    if (!(theta_h < kPi / 2.0)) return 0.0;
    const double y = std::sqrt(theta_h / (kPi / 2.0));
    const double x = std::fabs(std::atan2(h.y, h.x)) / kPi;
    const SlicePair sp = slices_for(view_elevation(std::sqrt(wo.x * wo.x + wo.y * wo.y), wo));
    const double xc = x < kBelowOne ? x : kBelowOne;
    const double p_xy = (1.0 - sp.t) * slices_[sp.k0].pdf(xc, y) + sp.t * slices_[sp.k1].pdf(xc, y);
    const double jac = 4.0 * dot(wo, hw) * 2.0 * kPi * kPi * y * std::sin(theta_h);
    const double p = p_xy / jac;
    return std::isfinite(p) && p > 0.0 ? p : 0.0;
}

double HalfVectorSampler::pdf(const Vec3& wo, const Vec3& wi) const {
    return options_.cosine_share * wi.z / kPi + (1.0 - options_.cosine_share) * data_pdf(wo, wi);
}

HalfVectorSampler::Draw HalfVectorSampler::draw(const Vec3& wo, double u1, double u2) const {
    // Each path builds its result whole: a Draw zeroed up front cost a `rep stos` per draw.
    const double share = options_.cosine_share;
    if (u1 < share) {
        const double v = u1 / share, r = std::sqrt(v), phi = 2.0 * kPi * u2;
        const Vec3 wi{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::fmax(0.0, 1.0 - v))};
        return wi.z > 0.0 ? Draw{{wi, pdf(wo, wi), {}}} : Draw{};
    }
    double v1 = (u1 - share) / (1.0 - share);
    const double sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    const SlicePair sp = slices_for(view_elevation(sin_o, wo));
    const bool upper = !(v1 < 1.0 - sp.t);
    v1 = upper ? (v1 - (1.0 - sp.t)) / sp.t : v1 / (1.0 - sp.t);
    // One bit of u2 picks the side of wo's plane; the rest drives the column.
    const double sign = u2 < 0.5 ? 1.0 : -1.0;
    const double v2 = u2 < 0.5 ? 2.0 * u2 : 2.0 * u2 - 1.0;
    const Piecewise2D::Point p = slices_[upper ? sp.k1 : sp.k0].sample(v1 < kBelowOne ? v1 : kBelowOne, v2);
    // half_at(p.x, p.y, sign), with table-based sines and cosines (sinθh is also the Jacobian's).
    const detail::SinCosTable& table = half_turn();
    const detail::SinCosTable::SinCos th = table(kPi / 2.0 * p.y * p.y), ph = table(kPi * p.x);
    const double sin_p = sign * ph.s;
    const Vec3 h = Azimuth(wo, sin_o).to_world({th.s * ph.c, th.s * sin_p, th.c});
    const double cos_d = dot(wo, h);
    const Vec3 wi = (2.0 * cos_d) * h - wo;  // reflect(wo, h)
    if (!(wi.z > 0.0)) return {};
    // The pdf from what is known here (the cell, θh, h) rather than by inverting wi again: the same
    // value pdf(wo, wi) computes, without its atan2 and elevation calls. Both slices share the grid,
    // so the other slice's density is that of the same cell.
    const double p_other = slices_[upper ? sp.k0 : sp.k1].density(p.row, p.col);
    const double p_xy = upper ? (1.0 - sp.t) * p_other + sp.t * p.pdf : (1.0 - sp.t) * p.pdf + sp.t * p_other;
    const double jac = 4.0 * cos_d * 2.0 * kPi * kPi * p.y * th.s;
    const double data = p_xy / jac;
    if (!(std::isfinite(data) && data > 0.0)) return {};
    return {{wi, share * wi.z / kPi + (1.0 - share) * data, {}}, true, th.s, th.c, sin_p, ph.c, sin_o, wo.z};
}

}  // namespace brdfz
