#include "brdfz/sample/lobes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "brdfz/repr/analytic/catalogue.h"
#include "brdfz/repr/analytic/model.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInvSqrtPi = 0.56418958354775628695;  // 1/√π

Vec3 reflect(const Vec3& wo, const Vec3& h) { return (2.0 * dot(wo, h)) * h - wo; }

// Unit half vector of wo and w, or false where it is undefined (w = −wo).
bool half_of(const Vec3& wo, const Vec3& w, Vec3& h) {
    const Vec3 s = wo + w;
    const double n2 = dot(s, s);
    if (!(n2 > 1e-30)) return false;
    h = (1.0 / std::sqrt(n2)) * s;
    return true;
}

// Orthonormal basis around a unit vector (Duff et al., JCGT 2017): no branch on the pole.
struct Basis {
    Vec3 t, b, n;
    explicit Basis(const Vec3& n_) : n(n_) {
        const double sign = std::copysign(1.0, n.z);
        const double a = -1.0 / (sign + n.z), c = n.x * n.y * a;
        t = {1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
        b = {c, sign + n.y * n.y * a, -n.y};
    }
    Vec3 to_world(const Vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

// Direction at polar angle cosine c (around +z) and azimuth 2π u.
Vec3 around_z(double c, double u) {
    const double s = std::sqrt(std::fmax(0.0, 1.0 - c * c)), phi = 2.0 * kPi * u;
    return {s * std::cos(phi), s * std::sin(phi), c};
}

// Half-vector samplers draw h from an isotropic (or φ → φ+π symmetric) density p_h over the upper
// hemisphere. An h facing away from wo is turned half a revolution about the normal, which faces it
// toward wo (wo·h' = 2 cosθo cosθh − wo·h > 0); that half of p_h's mass lands on h' too.
Vec3 reflect_about_drawn_half(const Vec3& wo, Vec3 h) {
    if (!(dot(wo, h) > 0.0)) h = {-h.x, -h.y, h.z};
    return reflect(wo, h);
}

// The density over wi of reflect_about_drawn_half, given p_h at w's half vector.
template <typename HalfDensity>
double reflected_density(const Vec3& wo, const Vec3& w, HalfDensity&& p_h) {
    Vec3 h;
    if (!half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
    const double folded = dot(wo, Vec3{-h.x, -h.y, h.z}) > 0.0 ? 1.0 : 2.0;
    return folded * p_h(h) / (4.0 * dot(wo, h));
}

// Solves cdf(x) = target on [lo, hi] for an increasing cdf, by Newton steps kept inside a shrinking
// bracket (bisection when a step would leave it). `eval(x, c, d)` sets c = cdf(x) and d = cdf'(x).
template <typename Eval>
double invert_cdf(Eval&& eval, double target, double lo, double hi, double x) {
    for (int it = 0; it < 100; ++it) {
        double c, d;
        eval(x, c, d);
        if (c == target) return x;
        (c > target ? hi : lo) = x;
        double next = x - (c - target) / d;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::fabs(next - x) <= 1e-13 * std::fmax(1.0, std::fabs(x)) || !(hi - lo > 1e-14)) return next;
        x = next;
    }
    return x;
}

// --- lambert ------------------------------------------------------------------------------------
struct CosineSampler {
    static Vec3 sample(const double*, const Vec3&, double u1, double u2) { return cosine_hemisphere(u1, u2); }
    static double density(const double*, const Vec3&, const Vec3& w) { return w.z > 0.0 ? w.z / kPi : 0.0; }
};

// --- GGX visible normals ------------------------------------------------------------------------
// Visible normals of the stretched (α = 1) configuration are uniform on a spherical cap seen from
// the stretched wo; stretching the cap point back gives h (Dupuy & Benyoub 2023). Their density is
// D_wo(h) = G1(wo) (wo·h) D(h) / cosθo, so pdf(wi) = D_wo(h) / (4 wo·h) = D(h) / (2 (cosθo + L)),
// L = √(cos²θo + αx² wo.x² + αy² wo.y²), with the exact Smith G1 = 2 cosθo / (cosθo + L).
Vec3 ggx_visible_sample(const Vec3& wo, double ax, double ay, double u1, double u2) {
    const Vec3 v = normalize({ax * wo.x, ay * wo.y, wo.z});
    const double z = (1.0 - u2) * (1.0 + v.z) - v.z;
    const Vec3 c = around_z(z, u1);
    const Vec3 hs = c + v;
    const Vec3 h = normalize({ax * hs.x, ay * hs.y, hs.z});
    return reflect(wo, h);
}

double ggx_visible_density(const Vec3& wo, const Vec3& w, double ax, double ay) {
    Vec3 h;
    if (!half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
    const double l = std::sqrt(wo.z * wo.z + ax * ax * wo.x * wo.x + ay * ay * wo.y * wo.y);
    return microfacet::ggx_aniso_d(h.x, h.y, h.z, ax, ay) / (2.0 * (wo.z + l));
}

struct GgxSampler {  // params: ks (3), alpha, ...
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        return ggx_visible_sample(wo, p[3], p[3], u1, u2);
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        return ggx_visible_density(wo, w, p[3], p[3]);
    }
};

struct GgxAnisoSampler {  // params: ks (3), alpha_x, alpha_y, f0
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        return ggx_visible_sample(wo, p[3], p[4], u1, u2);
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        return ggx_visible_density(wo, w, p[3], p[4]);
    }
};

// --- Beckmann visible normals -------------------------------------------------------------------
// In the stretched configuration (α = 1, wo at polar angle θ in the xz-plane) slopes (x, y) of
// visible normals m ∝ (−x, −y, 1) have density ∝ exp(−x² − y²) (cosθ − x sinθ) for x < cotθ: y is
// normal with variance ½, and x has the CDF ∝ M(x) = ½ cosθ erfc(−x) + sinθ exp(−x²) / (2√π), whose
// total M(cotθ) = cosθ (1 + Λ(θ)) (Heitz & d'Eon 2014). Both are inverted numerically to 1e-13.
// pdf(wi) = D(h) / (4 cosθo (1 + Λ(wo))) with the exact Λ; cosθo (1 + Λ) = M(cotθo) at α is written
// without dividing by cosθo or sinθo, so it stays finite at the pole and at grazing.
constexpr double kSlopeRange = 8.0;  // |slope| beyond 8 (in α units) carries e^-64 of the mass

// Winitzki's closed-form approximation of erf⁻¹(2u − 1) (relative error < 2e-3): a starting point
// from which Newton needs about three steps. 1 − z² is formed as 4u(1 − u) to keep the tails exact.
double inverse_erf_guess(double u) {
    constexpr double a = 0.147;
    const double l = std::log(4.0 * u * (1.0 - u)), t = 2.0 / (kPi * a) + 0.5 * l;
    return std::clamp(std::copysign(std::sqrt(std::sqrt(t * t - l / a) - t), u - 0.5), -kSlopeRange, kSlopeRange);
}

double beckmann_visible_norm(const Vec3& wo, double alpha) {
    const double s = std::sqrt(wo.x * wo.x + wo.y * wo.y), a = wo.z / (alpha * s);  // a = ∞ at the pole
    return 0.5 * wo.z * std::erfc(-a) + alpha * s * std::exp(-a * a) * (0.5 * kInvSqrtPi);
}

struct BeckmannSampler {  // params: ks (3), alpha, ...
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double alpha = p[3];
        const Vec3 v = normalize({alpha * wo.x, alpha * wo.y, wo.z});
        const double sin_v = std::sqrt(v.x * v.x + v.y * v.y), cos_v = v.z;
        const double hi = sin_v > 0.0 ? std::fmin(cos_v / sin_v, kSlopeRange) : kSlopeRange;
        const auto m = [&](double x, double& c, double& d) {
            const double g = std::exp(-x * x);
            c = 0.5 * cos_v * std::erfc(-x) + sin_v * g * (0.5 * kInvSqrtPi);
            d = g * (cos_v - x * sin_v) * kInvSqrtPi;
        };
        double m_hi, unused;
        m(hi, m_hi, unused);
        // Start between the two limits: a normal slope at the pole, −√(−ln u) (CDF exp(−x²)) at grazing.
        const double t = sin_v * sin_v;
        const double guess = (1.0 - t) * inverse_erf_guess(u1) - t * std::sqrt(-std::log(std::fmax(u1, 1e-300)));
        const double x = invert_cdf(m, u1 * m_hi, -kSlopeRange, hi, std::clamp(guess, -kSlopeRange, hi));
        const auto gauss = [](double y, double& c, double& d) {
            c = 0.5 * std::erfc(-y);
            d = std::exp(-y * y) * kInvSqrtPi;
        };
        const double y = invert_cdf(gauss, u2, -kSlopeRange, kSlopeRange, inverse_erf_guess(u2));
        // Rotate the slopes to wo's azimuth and unstretch them.
        const double cp = sin_v > 0.0 ? v.x / sin_v : 1.0, sp = sin_v > 0.0 ? v.y / sin_v : 0.0;
        const Vec3 h = normalize({-alpha * (cp * x - sp * y), -alpha * (sp * x + cp * y), 1.0});
        return reflect(wo, h);
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        Vec3 h;
        if (!half_of(wo, w, h) || !(h.z > 0.0)) return 0.0;
        return microfacet::beckmann_d(h.z, p[3]) / (4.0 * beckmann_visible_norm(wo, p[3]));
    }
};

// --- Blinn-Phong: p_h = (n+2)/(2π) cos^(n+1) θh, cosθh = u^(1/(n+2)) ---------------------------
struct BlinnPhongSampler {  // params: ks (3), n
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double c = std::exp(std::log1p(-u1) / (p[3] + 2.0));
        return reflect_about_drawn_half(wo, around_z(c, u2));
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        const double n = p[3];
        return reflected_density(wo, w, [n](const Vec3& h) {
            return (n + 2.0) * (0.5 / kPi) * std::exp((n + 1.0) * std::log(h.z));
        });
    }
};

// --- Ward: the Beckmann p_h = D(h) cosθh, tan²θh = −α² ln(1 − u) ---------------------------------
struct WardSampler {  // params: ks (3), alpha
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double tan2 = -p[3] * p[3] * std::log1p(-u1);
        return reflect_about_drawn_half(wo, around_z(1.0 / std::sqrt(1.0 + tan2), u2));
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        const double alpha = p[3];
        return reflected_density(wo, w, [alpha](const Vec3& h) { return microfacet::beckmann_d(h.z, alpha) * h.z; });
    }
};

// --- Ashikhmin-Shirley ----------------------------------------------------------------------------
// The paper's specular density p_h = √((nu+1)(nv+1))/(2π) cosθh^(nu cos²φ + nv sin²φ) (sampled by its
// closed-form inversion), or cosine sampling for the diffuse part. The share of the specular part is
// its albedo over the total by a closed-form estimate: Fresnel averaged over the cosine-weighted
// hemisphere, Rs + (1 − Rs)/21, against the diffuse term's Rd (1 − Rs), both averaged over channels.
double ashikhmin_shirley_specular_share(const double* p) {
    double spec = 0.0, diff = 0.0;
    for (int c = 0; c < 3; ++c) {
        spec += p[3 + c] + (1.0 - p[3 + c]) / 21.0;
        diff += p[c] * (1.0 - p[3 + c]);
    }
    return spec / (spec + diff);
}

struct AshikhminShirleySampler {  // params: rd (3), rs (3), nu, nv
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        const double share = ashikhmin_shirley_specular_share(p);
        if (!(u1 < share)) return cosine_hemisphere(std::fmin((u1 - share) / (1.0 - share), std::nextafter(1.0, 0.0)), u2);
        // φ in one quadrant by the paper's inversion, the quadrant from the top two bits of u.
        const double v = 4.0 * u1 / share;
        const int quadrant = std::min(static_cast<int>(v), 3);
        const double phi0 = std::atan(std::sqrt((p[6] + 1.0) / (p[7] + 1.0)) * std::tan(0.5 * kPi * (v - quadrant)));
        const double phi = quadrant == 0 ? phi0 : quadrant == 1 ? kPi - phi0 : quadrant == 2 ? kPi + phi0 : 2.0 * kPi - phi0;
        const double cp = std::cos(phi), sp = std::sin(phi);
        const double e = p[6] * cp * cp + p[7] * sp * sp;
        const double c = std::exp(std::log1p(-u2) / (e + 1.0)), s = std::sqrt(std::fmax(0.0, 1.0 - c * c));
        return reflect_about_drawn_half(wo, {s * cp, s * sp, c});
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        const double share = ashikhmin_shirley_specular_share(p);
        const double nu = p[6], nv = p[7];
        const double spec = reflected_density(wo, w, [nu, nv](const Vec3& h) {
            const double xy = std::fmax(h.x * h.x + h.y * h.y, kTiny);
            const double e = (nu * h.x * h.x + nv * h.y * h.y) / xy;
            return std::sqrt((nu + 1.0) * (nv + 1.0)) * (0.5 / kPi) * std::exp(e * std::log(h.z));
        });
        return share * spec + (1.0 - share) * CosineSampler::density(p, wo, w);
    }
};

// --- Lafortune: (n+1)/(2π) (w·â)^n around â = a/|a|, a = (cxy wo.x, cxy wo.y, cz wo.z) -------------
// The lobe is |a|^n (wi·â)^n; where a vanishes so does the lobe, and cosine sampling stands in.
struct LafortuneSampler {  // params: rho (3), cxy, cz, n
    static bool axis(const double* p, const Vec3& wo, Vec3& a) {
        a = {p[3] * wo.x, p[3] * wo.y, p[4] * wo.z};
        const double len = length(a);
        if (!(len > 1e-12)) return false;
        a = (1.0 / len) * a;
        return true;
    }
    static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2) {
        Vec3 a;
        if (!axis(p, wo, a)) return cosine_hemisphere(u1, u2);
        return Basis(a).to_world(around_z(std::exp(std::log1p(-u1) / (p[5] + 1.0)), u2));
    }
    static double density(const double* p, const Vec3& wo, const Vec3& w) {
        Vec3 a;
        if (!axis(p, wo, a)) return CosineSampler::density(p, wo, w);
        const double c = dot(w, a);
        return c > 0.0 ? (p[5] + 1.0) * (0.5 / kPi) * std::exp(p[5] * std::log(c)) : 0.0;
    }
};

// Family -> sampler. A family without one fails to compile here.
template <typename Family>
struct SamplerOf;
template <>
struct SamplerOf<lobes::Lambert> : CosineSampler {};
template <>
struct SamplerOf<lobes::BlinnPhong> : BlinnPhongSampler {};
template <>
struct SamplerOf<lobes::Ward> : WardSampler {};
template <typename Fresnel, lobes::detail::Name kName>
struct SamplerOf<lobes::Microfacet<lobes::GgxCorrelated, Fresnel, kName>> : GgxSampler {};
template <typename Fresnel, lobes::detail::Name kName>
struct SamplerOf<lobes::Microfacet<lobes::GgxSeparable, Fresnel, kName>> : GgxSampler {};
template <typename Fresnel, lobes::detail::Name kName>
struct SamplerOf<lobes::Microfacet<lobes::BeckmannSeparable, Fresnel, kName>> : BeckmannSampler {};
template <>
struct SamplerOf<lobes::GgxAniso> : GgxAnisoSampler {};
template <>
struct SamplerOf<lobes::AshikhminShirley> : AshikhminShirleySampler {};
template <>
struct SamplerOf<lobes::Lafortune> : LafortuneSampler {};

template <typename... Families>
constexpr std::array<LobeSampler, sizeof...(Families)> samplers_of(LobeList<Families...>) {
    return {LobeSampler{&SamplerOf<Families>::sample, &SamplerOf<Families>::density}...};
}
constexpr auto kSamplers = samplers_of(AllLobes{});

double mean(const double v[3]) { return (v[0] + v[1] + v[2]) / 3.0; }

}  // namespace

const LobeSampler& lobe_sampler(const LobeType& type) {
    return kSamplers[static_cast<std::size_t>(&type - lobe_types().data())];
}

LobeMixture::LobeMixture(const Model& model, std::span<const double> params)
    : params_(params.begin(), params.end()) {
    for (const Model::Term& t : model.terms()) terms_.push_back({t.type, lobe_sampler(*t.type), t.offset});
    // Albedo of each lobe at each node, estimated with its own sampler over a fixed stratified set of
    // (u1, u2), with wo's azimuth varied too (anisotropic lobes): deterministic and cheap.
    const std::size_t n = terms_.size();
    albedo_.assign(kAlbedoNodes * n, 0.0);
    constexpr int kSide = 16;
    static_assert(kSide * kSide == kAlbedoSamples);
    for (int k = 0; k < kAlbedoNodes; ++k) {
        const double cos_o = (k + 0.5) / kAlbedoNodes, sin_o = std::sqrt(1.0 - cos_o * cos_o);
        for (std::size_t j = 0; j < n; ++j) {
            const Term& t = terms_[j];
            const double* p = params_.data() + t.offset;
            double sum = 0.0;
            for (int i = 0; i < kAlbedoSamples; ++i) {
                const double phi_o = 2.0 * kPi * std::fmod(i * 0.6180339887498949, 1.0);
                const Vec3 wo{sin_o * std::cos(phi_o), sin_o * std::sin(phi_o), cos_o};
                Vec3 wi = t.sampler.sample(p, wo, (i % kSide + 0.5) / kSide, (i / kSide + 0.5) / kSide);
                wi.z = std::fabs(wi.z);
                const double pdf = folded_density(t, wo, wi);
                if (!(wi.z > 0.0 && pdf > 0.0)) continue;
                double f[3];
                t.type->eval(make_geometry(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z), p, f);
                sum += mean(f) * wi.z / pdf;
            }
            const double a = sum / kAlbedoSamples;
            albedo_[k * n + j] = std::isfinite(a) && a > 0.0 ? a : 0.0;
        }
    }
}

double LobeMixture::folded_density(const Term& t, const Vec3& wo, const Vec3& wi) const {
    const double* p = params_.data() + t.offset;
    return t.sampler.density(p, wo, wi) + t.sampler.density(p, wo, {wi.x, wi.y, -wi.z});
}

bool LobeMixture::lobe_weights(const Vec3& wo, double* w) const {
    const std::size_t n = terms_.size();
    const double pos = std::clamp(wo.z * kAlbedoNodes - 0.5, 0.0, kAlbedoNodes - 1.0);
    const int k0 = std::min(static_cast<int>(pos), kAlbedoNodes - 2);
    const double t = pos - k0;
    double total = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
        w[j] = (1.0 - t) * albedo_[k0 * n + j] + t * albedo_[(k0 + 1) * n + j];
        total += w[j];
    }
    if (!(total > 0.0)) return false;
    for (std::size_t j = 0; j < n; ++j) w[j] /= total;
    return true;
}

std::vector<double> LobeMixture::weights(const Vec3& wo) const {
    std::vector<double> w(terms_.size());
    if (!lobe_weights(wo, w.data())) std::fill(w.begin(), w.end(), 0.0);
    return w;
}

double LobeMixture::pdf(const Vec3& wo, const Vec3& wi) const {
    double w[Model::kMaxTerms];
    if (!lobe_weights(wo, w)) return CosineSampler::density(nullptr, wo, wi);
    double pdf = 0.0;
    for (std::size_t j = 0; j < terms_.size(); ++j)
        if (w[j] > 0.0) pdf += w[j] * folded_density(terms_[j], wo, wi);
    return pdf;
}

BrdfSample LobeMixture::sample(const Vec3& wo, double u1, double u2) const {
    double w[Model::kMaxTerms];
    Vec3 wi;
    if (!lobe_weights(wo, w)) {
        wi = cosine_hemisphere(u1, u2);
    } else {
        // u1 picks the lobe; its position inside the lobe's share, rescaled, drives the lobe's sampler.
        std::size_t j = 0;
        double start = 0.0;
        while (j + 1 < terms_.size() && !(u1 < start + w[j])) start += w[j++];
        while (!(w[j] > 0.0)) --j;  // rounding past the last non-empty lobe
        const double v = std::clamp((u1 - start) / w[j], 0.0, std::nextafter(1.0, 0.0));
        const Term& t = terms_[j];
        wi = t.sampler.sample(params_.data() + t.offset, wo, v, u2);
        wi.z = std::fabs(wi.z);
    }
    const double p = pdf(wo, wi);
    if (!(wi.z > 0.0 && std::isfinite(p) && p > 0.0)) return {};
    return {wi, p, {}};
}

}  // namespace brdfz
