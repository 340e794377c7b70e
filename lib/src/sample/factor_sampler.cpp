#include "brdfz/sample/factor_sampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/repr/factored.h"
#include "detail/azimuth.h"
#include "detail/fast_math.h"
#include "detail/table_lookup.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;

using detail::Azimuth;
using detail::reflect;

// fn(wi, h) for the half vectors at s = sin²(θh/2) and n_phi azimuths at cell centres over [0, π]
// (the slices are symmetric in φh) whose reflection of wo lies above the horizon.
template <typename Fn>
void for_each_reflection(const Vec3& wo, double s, int n_phi, Fn&& fn) {
    const double cos_h = 1.0 - 2.0 * s, sin_h = 2.0 * std::sqrt(s * (1.0 - s));
    for (int p = 0; p < n_phi; ++p) {
        const double phi = (p + 0.5) / n_phi * kPi;
        const Vec3 h{sin_h * std::cos(phi), sin_h * std::sin(phi), cos_h};
        const Vec3 wi = reflect(wo, h);
        if (wi.z > 0.0) fn(wi, h);
    }
}

// s = sin²(θ/2) = (1 − cosθ)/2, the coordinate in which solid angle is uniform (dω = 2 ds dφ).
double s_of_theta(double theta) {
    const double h = std::sin(theta / 2.0);
    return h * h;
}

// s of the largest θh that reflects wo above the horizon for some azimuth: at φh = 0,
// wi.z = sinθo·sin2θh + cosθo·cos2θh = cos(2θh − θo) > 0  ⇔  θh < θmax = π/4 + θo/2. Without
// trigonometric calls: s = (1 − cosθmax)/2 with cosθmax = (cos½θo − sin½θo)/√2, the half angles from cosθo.
double max_s(double cos_o) {
    const double c = std::sqrt(0.5 * (1.0 + cos_o)), s = std::sqrt(std::fmax(0.0, 0.5 * (1.0 - cos_o)));
    return 0.5 * (1.0 - (c - s) * std::numbers::sqrt2 / 2.0);
}

// At θh (given by s) and θo, wi.z = A + B·cosφh with A = cosθo·cos2θh, B = sinθo·sin2θh ≥ 0: wi is above
// the horizon for |φh| < phi_max, and the azimuth density ∝ wi.z there has normaliser
// norm = ∫ (A + B cosφ) dφ = 2(A·phi_max + B·sin phi_max); norm = 0 when no azimuth is above.
struct AzimuthRange {
    double a, b, phi_max, norm;
};
AzimuthRange azimuth_range(double cos_o, double sin_o, double s) {
    const double sin2_h = 4.0 * s * (1.0 - s);  // sin²θh
    const double a = cos_o * (1.0 - 2.0 * sin2_h), b = sin_o * 2.0 * std::sqrt(sin2_h) * (1.0 - 2.0 * s);
    if (a >= b) return {a, b, kPi, 2.0 * kPi * a};
    if (a <= -b) return {a, b, 0.0, 0.0};
    const double c = -a / b;
    const double phi_max = std::acos(c);
    return {a, b, phi_max, std::fmax(0.0, 2.0 * (a * phi_max + b * std::sqrt(1.0 - c * c)))};
}

// φ in [0, phi_max] with A·φ + B·sinφ = target (increasing there: its derivative is wi.z ≥ 0), by Newton's
// method kept inside a shrinking bracket. Converged when Newton's own step is small, tested before the
// bracket's safeguard, which would turn a converged step that lands on the bracket's edge into a
// bisection away from the root. sin and cos come from the table (2 ulp): libm's sincos would dominate
// the cost of a draw.
double solve_azimuth(const AzimuthRange& r, double target) {
    const detail::SinCosTable& table = detail::half_turn_sincos();
    double lo = 0.0, hi = r.phi_max, phi = r.phi_max * target / (0.5 * r.norm);
    for (int it = 0; it < 30; ++it) {
        const detail::SinCosTable::SinCos sc = table(phi);
        const double g = r.a * phi + r.b * sc.s - target;
        if (g > 0.0) hi = phi;
        else lo = phi;
        const double slope = r.a + r.b * sc.c;
        const double step = slope > 0.0 ? g / slope : std::numeric_limits<double>::infinity();
        if (std::fabs(step) <= 1e-13 * r.phi_max) return std::clamp(phi - step, lo, hi);
        double next = phi - step;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        phi = next;
    }
    return phi;
}

// A channel's value for its reconstruction y in the factor space, negatives clamped as eval does.
double to_value(FactorSpace space, double y) {
    const double p = y > 0.0 ? y : 0.0;
    switch (space) {
        case FactorSpace::Log: return std::expm1(p);
        case FactorSpace::Cbrt: return p * p * p;
        default: return p;
    }
}

// The largest i in [0, n) with a[i] <= x (0 when none), for ascending a. Branch-free (the compare
// selects): x is random, so a branchy search mispredicts about every other step.
int last_not_above(const double* a, int n, double x) {
    const double* base = a;
    for (int len = n; len > 1;) {
        const int half = len / 2;
        base = base[half] <= x ? base + half : base;
        len -= half;
    }
    return static_cast<int>(base - a);
}

// The terms T_j / a_j = u_j·v_j of the factorisation at (wi, wo), interpolated as FactoredBrdf's eval does.
class Terms {
public:
    explicit Terms(const Factors& f) : f_(f), m_(f.row_width()) {}

    void at(const Vec3& wi, const Vec3& wo, double* out) const {
        const GridSpec& g = f_.grid;
        const detail::Corners k = detail::linear_corners(g, detail::fast_bin_coords(g, wi, wo), wi, wo);
        std::size_t r[4], c[4];
        double rw[4], cw[4];
        const double h0 = 1.0 - k.h.t, d0 = 1.0 - k.d.t, p0 = 1.0 - k.p.t;
        if (f_.layout == FactorLayout::HxDP) {
            const std::size_t np = static_cast<std::size_t>(g.n_phi_d);
            r[0] = k.h.i0, r[1] = k.h.i1, r[2] = r[3] = 0;
            rw[0] = h0, rw[1] = k.h.t, rw[2] = rw[3] = 0.0;
            c[0] = k.d.i0 * np + k.p.i0, c[1] = k.d.i0 * np + k.p.i1, c[2] = k.d.i1 * np + k.p.i0,
            c[3] = k.d.i1 * np + k.p.i1;
            cw[0] = d0 * p0, cw[1] = d0 * k.p.t, cw[2] = k.d.t * p0, cw[3] = k.d.t * k.p.t;
        } else {
            const std::size_t nd = static_cast<std::size_t>(g.n_theta_d);
            r[0] = k.h.i0 * nd + k.d.i0, r[1] = k.h.i0 * nd + k.d.i1, r[2] = k.h.i1 * nd + k.d.i0,
            r[3] = k.h.i1 * nd + k.d.i1;
            rw[0] = h0 * d0, rw[1] = h0 * k.d.t, rw[2] = k.h.t * d0, rw[3] = k.h.t * k.d.t;
            c[0] = k.p.i0, c[1] = k.p.i1, c[2] = c[3] = 0;
            cw[0] = p0, cw[1] = k.p.t, cw[2] = cw[3] = 0.0;
        }
        for (std::size_t j = 0; j < m_; ++j) {
            double a = 0.0, b = 0.0;
            for (int i = 0; i < 4; ++i) a += rw[i] * f_.u[r[i] * m_ + j], b += cw[i] * f_.v[c[i] * m_ + j];
            out[j] = a * b;
        }
    }

private:
    const Factors& f_;
    std::size_t m_;
};

}  // namespace

FactorSampler::FactorSampler(const Factors& f, const FactorSamplerOptions& o) : options_(o) {
    if (o.n_theta_o < 2 || o.n_theta_o > 1024 || o.n_phi < 1 || o.n_phi > 4096)
        throw ValueError("factor sampler: resolutions out of range");
    if (!(o.cosine_share > 0.0 && o.cosine_share < 1.0))
        throw ValueError("factor sampler: cosine_share must be in (0, 1)");
    if (!(o.floor > 0.0 && o.floor < 1.0)) throw ValueError("factor sampler: floor must be in (0, 1)");
    if (o.density != FactorDensity::Mixture && o.density != FactorDensity::Marginal)
        throw ValueError("factor sampler: unknown density");
    const GridSpec& g = f.grid;
    const int rows = rows_ = g.n_theta_h, m = f.row_width(), K = o.n_theta_o;
    s_edges_.resize(rows + 1);
    for (int i = 0; i <= rows; ++i) s_edges_[i] = s_of_theta(g.theta_h_of_u(i));

    // Channel c's weight of term j (separate colour: 1 for its own channel's terms), and a_j, their mean.
    std::vector<double> mix(3 * static_cast<std::size_t>(m), 0.0), a(m, 0.0);
    for (int ch = 0; ch < 3; ++ch)
        for (int j = 0; j < m; ++j) {
            const double x = f.colour == FactorColour::Shared ? f.colour_weights[ch * f.rank + j]
                                                              : (j / f.rank == ch ? 1.0 : 0.0);
            mix[static_cast<std::size_t>(ch) * m + j] = x;
            a[j] += std::fabs(x) / 3.0;
        }

    // Each term's θh density per unit s at the row edges: |u_j| as eval interpolates it (layout hd_p:
    // averaged over its θd rows); between edges it is taken as linear in s, with mass total_j.
    const int nd = f.layout == FactorLayout::HDxP ? g.n_theta_d : 1;
    std::vector<double> edge(static_cast<std::size_t>(m) * (rows + 1)), total(m, 0.0);
    for (int j = 0; j < m; ++j)
        for (int i = 0; i <= rows; ++i) {
            const detail::Span sp = detail::clamped_span(i - g.sample_offset(), rows);
            double sum = 0.0;
            for (int d = 0; d < nd; ++d)
                sum += std::fabs((1.0 - sp.t) * f.u[(static_cast<std::size_t>(sp.i0) * nd + d) * m + j] +
                                 sp.t * f.u[(static_cast<std::size_t>(sp.i1) * nd + d) * m + j]);
            edge[static_cast<std::size_t>(j) * (rows + 1) + i] = sum / nd;
            if (i > 0)
                total[j] += 0.5 * (edge[static_cast<std::size_t>(j) * (rows + 1) + i - 1] + sum / nd) *
                            (s_edges_[i] - s_edges_[i - 1]);
        }

    // Per slice, Mixture: the terms' albedo shares W_j = ∫ |a_j T_j| cosθi dωi, by the midpoint rule over
    // (s, φh) on the rows × n_phi grid (dωi = 4 (wo·h) dωh, dωh = 2 ds dφ; constants dropped), then the
    // mixture Σ_j W_j·|u_j|/total_j.
    const Terms terms(f);
    theta_o_.resize(K);
    cdf_.assign(static_cast<std::size_t>(K) * (rows + 1), 0.0);
    density_.assign(static_cast<std::size_t>(K) * (rows + 1), 0.0);
    std::vector<double> w(m), t(m);
    for (int k = 0; k < K; ++k) {
        theta_o_[k] = kMaxThetaODeg * kPi / 180.0 * k / (K - 1);
        const Vec3 wo = spherical_direction(theta_o_[k], 0.0);
        double* d = &density_[static_cast<std::size_t>(k) * (rows + 1)];
        if (o.density == FactorDensity::Mixture) {
            std::fill(w.begin(), w.end(), 0.0);
            for (int r = 0; r < rows; ++r) {
                const double ds = s_edges_[r + 1] - s_edges_[r];
                for_each_reflection(wo, s_edges_[r] + 0.5 * ds, o.n_phi, [&](const Vec3& wi, const Vec3& h) {
                    terms.at(wi, wo, t.data());
                    const double jac = wi.z * dot(wo, h) * ds;
                    for (int j = 0; j < m; ++j) w[j] += std::fabs(a[j] * t[j]) * jac;
                });
            }
            for (int j = 0; j < m; ++j)
                if (total[j] > 0.0)
                    for (int i = 0; i <= rows; ++i)
                        d[i] += w[j] / total[j] * edge[static_cast<std::size_t>(j) * (rows + 1) + i];
        } else {
            // At each row edge, the integrand f·cosθi·(wo·h) of the reconstruction (mean channel, in the
            // value domain) summed over φh: the θh marginal, per unit s, of what the data wants drawn.
            for (int i = 0; i < rows; ++i)
                for_each_reflection(wo, s_edges_[i], o.n_phi, [&](const Vec3& wi, const Vec3& h) {
                    terms.at(wi, wo, t.data());
                    double value = 0.0;
                    for (int ch = 0; ch < 3; ++ch) {
                        double y = 0.0;
                        for (int j = 0; j < m; ++j) y += mix[static_cast<std::size_t>(ch) * m + j] * t[j];
                        value += to_value(f.space, y);
                    }
                    d[i] += value * wi.z * dot(wo, h);
                });
        }
        double mass = 0.0;
        for (int r = 0; r < rows; ++r) mass += 0.5 * (d[r] + d[r + 1]) * (s_edges_[r + 1] - s_edges_[r]);
        // The floor: uniform in s over [0, ½]; all of the density when the factors give nothing.
        const double floor = mass > 0.0 ? o.floor * mass / (1.0 - o.floor) * 2.0 : 2.0;
        double* c = &cdf_[static_cast<std::size_t>(k) * (rows + 1)];
        for (int i = 0; i <= rows; ++i) d[i] += floor;
        for (int r = 0; r < rows; ++r) c[r + 1] = c[r] + 0.5 * (d[r] + d[r + 1]) * (s_edges_[r + 1] - s_edges_[r]);
        const double norm = c[rows];
        if (!(std::isfinite(norm) && norm > 0.0)) throw ValueError("factor sampler: the factors give no finite density");
        for (int i = 0; i <= rows; ++i) c[i] /= norm, d[i] /= norm;
        c[rows] = 1.0;
    }
}

std::size_t FactorSampler::nbytes() const {
    return (s_edges_.size() + theta_o_.size() + cdf_.size() + density_.size()) * sizeof(double);
}

FactorSampler::SlicePair FactorSampler::slices_for(const Vec3& wo) const {
    const int K = static_cast<int>(theta_o_.size());
    const double pos = std::fmin(std::fmax(elevation(wo) / theta_o_[K - 1] * (K - 1), 0.0), K - 1.0);
    const int k0 = std::min(static_cast<int>(pos), K - 2);
    return {k0, k0 + 1, pos - k0};
}

int FactorSampler::row_of(double s) const { return last_not_above(s_edges_.data(), rows_, s); }

double FactorSampler::cdf_at(int k, int r, double s) const {
    const std::size_t base = static_cast<std::size_t>(k) * (rows_ + 1);
    const double ds = s_edges_[r + 1] - s_edges_[r];
    const double x = std::clamp(s - s_edges_[r], 0.0, ds);
    const double d0 = density_[base + r], d1 = density_[base + r + 1];
    return cdf_[base + r] + x * (d0 + 0.5 * (d1 - d0) * x / ds);
}

double FactorSampler::density_at(int k, int r, double s) const {
    const std::size_t base = static_cast<std::size_t>(k) * (rows_ + 1);
    const double d0 = density_[base + r], d1 = density_[base + r + 1];
    return d0 + (d1 - d0) * (s - s_edges_[r]) / (s_edges_[r + 1] - s_edges_[r]);
}

double FactorSampler::half_density(const SlicePair& sp, int r, double s, int r_max, double s_max, double wi_z,
                                   double norm) const {
    double p = 0.0;
    for (const auto& [k, w] : {std::pair{sp.k0, 1.0 - sp.t}, std::pair{sp.k1, sp.t}})
        if (w > 0.0) p += w * density_at(k, r, s) / cdf_at(k, r_max, s_max);
    return 0.5 * p * wi_z / norm;  // the azimuth's density wi.z/norm, and dωh = 2 ds dφ
}

double FactorSampler::pdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 hw = half_vector(wi, wo);
    const Vec3 h = Azimuth(wo).to_local(hw);
    const double s = (h.x * h.x + h.y * h.y) / (2.0 * (1.0 + h.z));  // (1 − cosθh)/2 without cancellation
    const double cos_o = wo.z, sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    const double s_max = max_s(cos_o);
    const AzimuthRange az = azimuth_range(cos_o, sin_o, s);
    const double data = s < s_max && az.norm > 0.0
                            ? half_density(slices_for(wo), row_of(s), s, row_of(s_max), s_max, wi.z, az.norm) /
                                  (4.0 * dot(wo, hw))
                            : 0.0;
    const double share = options_.cosine_share;
    return share * wi.z / kPi + (1.0 - share) * (std::isfinite(data) && data > 0.0 ? data : 0.0);
}

BrdfSample FactorSampler::sample(const Vec3& wo, double u1, double u2) const {
    const double share = options_.cosine_share;
    if (u1 < share) {
        const double v = u1 / share, r = std::sqrt(v), phi = 2.0 * kPi * u2;
        const Vec3 wi{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::fmax(0.0, 1.0 - v))};
        return wi.z > 0.0 ? BrdfSample{wi, pdf(wo, wi), {}} : BrdfSample{};
    }
    // u1 picks the slice, then θh; u2 the side of wo's plane, then the azimuth.
    double v = (u1 - share) / (1.0 - share);
    const SlicePair sp = slices_for(wo);
    const bool upper = !(v < 1.0 - sp.t);
    v = std::fmin(upper ? (v - (1.0 - sp.t)) / sp.t : v / (1.0 - sp.t), std::nextafter(1.0, 0.0));
    const int k = upper ? sp.k1 : sp.k0;
    const double cos_o = wo.z, sin_o = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    const double s_max = max_s(cos_o);
    const int r_max = row_of(s_max);
    // Inversion of the CDF truncated at s_max: the row, then s within it.
    const double x = v * cdf_at(k, r_max, s_max);
    const double* c = &cdf_[static_cast<std::size_t>(k) * (rows_ + 1)];
    const int r = last_not_above(c, r_max + 1, x);  // every row has mass (the floor): x < c[r + 1]
    // The density is linear across the row, d0 + a·(s − s_r): solve d0·y + a·y²/2 = x − c[r] for y in
    // the form without cancellation.
    const double* d = &density_[static_cast<std::size_t>(k) * (rows_ + 1)];
    const double ds = s_edges_[r + 1] - s_edges_[r], a = (d[r + 1] - d[r]) / ds, mass = x - c[r];
    const double root = d[r] + std::sqrt(std::fmax(0.0, d[r] * d[r] + 2.0 * a * mass));
    const double y = root > 0.0 ? 2.0 * mass / root : 0.0;
    const double s = std::fmin(s_edges_[r] + std::clamp(y, 0.0, ds), s_max);
    const AzimuthRange az = azimuth_range(cos_o, sin_o, s);
    if (!(az.norm > 0.0)) return {};
    const double side = u2 < 0.5 ? 1.0 : -1.0, w2 = u2 < 0.5 ? 2.0 * u2 : 2.0 * u2 - 1.0;
    const detail::SinCosTable::SinCos phi = detail::half_turn_sincos()(solve_azimuth(az, w2 * 0.5 * az.norm));
    const double sin_h = 2.0 * std::sqrt(s * (1.0 - s)), cos_h = 1.0 - 2.0 * s;
    const Vec3 h = Azimuth(wo).to_world({sin_h * phi.c, sin_h * side * phi.s, cos_h});
    const Vec3 wi = reflect(wo, h);
    if (!(wi.z > 0.0)) return {};
    // The density is continuous in s, so row r serves even when s rounded onto its upper edge.
    const double data = half_density(sp, r, s, r_max, s_max, wi.z, az.norm) / (4.0 * dot(wo, h));
    if (!(std::isfinite(data) && data > 0.0)) return {};
    return {wi, share * wi.z / kPi + (1.0 - share) * data, {}};
}

}  // namespace brdfz
