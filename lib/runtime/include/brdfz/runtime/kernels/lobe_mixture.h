// Analytic models as brdfz::runtime holds them: a sum of lobes (kernels/lobes/), evaluated as the sum
// of the lobes' values and importance-sampled by a mixture of the lobes' own samplers. The one source
// of a single call's eval, sample and pdf: the core's AnalyticBrdf and LobeMixture (sample/lobes.h)
// call these functions, and their batch kernels share the pieces (albedo_nodes, lobe_albedo,
// choose_lobe, folded_pdf), so that the two agree to the bit.
//
// The mixture picks a lobe with probability ∝ its directional albedo (mean over channels) at wo,
// interpolated linearly in cosθo from a table at kAlbedoNodes nodes, node k at cosθo = (k + ½) /
// kAlbedoNodes (the core estimates it with each lobe's own sampler when it builds the model). A draw
// below the horizon is folded back (z → −z), so the density over the upper hemisphere is
// p(w) + p(w with −z): it integrates to exactly 1 and no sample is lost. A model that is black at wo
// (every albedo 0) is sampled with the cosine density.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "brdfz/runtime/kernels/lobes/families.h"
#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::runtime::kernels {

constexpr int kAlbedoNodes = 16;
constexpr std::size_t kMaxLobeTerms = 16;

// One lobe of a model: its family (kLobeFamilies' index) and the position of its first parameter.
struct LobeTerm {
    int family;
    std::size_t offset;
};

// A model with its sampler's table, wherever they are stored.
struct LobeMixtureView {
    const LobeTerm* terms = nullptr;
    std::size_t count = 0;           // number of terms, 1 to kMaxLobeTerms
    const double* params = nullptr;  // every term's parameters, each inside its family's bounds
    const double* albedo = nullptr;  // kAlbedoNodes × count, node-major: each lobe's albedo, finite and >= 0
};

struct LobeMixtureDraw {
    Vec3 wi;
    double pdf;  // 0: failed
};

// The table nodes on either side of cosθo: the lower one and the weight of the upper one.
struct AlbedoNodes {
    int k0;
    double t;
};
[[gnu::always_inline]] inline AlbedoNodes albedo_nodes(double cos_o) {
    const double pos = std::clamp(cos_o * kAlbedoNodes - 0.5, 0.0, kAlbedoNodes - 1.0);
    const int k0 = std::min(static_cast<int>(pos), kAlbedoNodes - 2);
    return {k0, pos - k0};
}

// Lobe j's albedo between the nodes n of a table of `count` lobes.
[[gnu::always_inline]] inline double lobe_albedo(const double* albedo, std::size_t count, std::size_t j,
                                                 const AlbedoNodes& n) {
    return (1.0 - n.t) * albedo[n.k0 * count + j] + n.t * albedo[(n.k0 + 1) * count + j];
}

// The lobe u1 in [0, 1) picks from the probabilities w[j·stride], j < count (not all 0), and v in
// [0, 1), u1's position inside that lobe's share, which drives the lobe's sampler.
struct LobeChoice {
    std::size_t lobe;
    double v;
};
[[gnu::always_inline]] inline LobeChoice choose_lobe(const double* w, std::size_t stride, std::size_t count,
                                                     double u1) {
    constexpr double kBelowOne = 0x1.fffffffffffffp-1;  // the double before 1
    std::size_t j = 0;
    double first = 0.0;
    while (j + 1 < count && !(u1 < first + w[j * stride])) first += w[j++ * stride];
    while (!(w[j * stride] > 0.0)) --j;  // rounding past the last non-empty lobe
    return {j, std::clamp((u1 - first) / w[j * stride], 0.0, kBelowOne)};
}

// The probability of each lobe at wo into w[0, count); false, with every w 0, when the model is black
// there.
inline bool lobe_mixture_weights(const LobeMixtureView& m, const Vec3& wo, double* w) {
    const AlbedoNodes n = albedo_nodes(wo.z);
    double total = 0.0;
    for (std::size_t j = 0; j < m.count; ++j) {
        w[j] = lobe_albedo(m.albedo, m.count, j, n);
        total += w[j];
    }
    if (!(total > 0.0)) {
        for (std::size_t j = 0; j < m.count; ++j) w[j] = 0.0;
        return false;
    }
    for (std::size_t j = 0; j < m.count; ++j) w[j] /= total;
    return true;
}

// The density of the lobes weighted by w (lobe_mixture_weights at wo) at wi.
inline double lobe_mixture_density(const LobeMixtureView& m, const double* w, const Vec3& wo, const Vec3& wi) {
    double pdf = 0.0;
    for (std::size_t j = 0; j < m.count; ++j)
        if (w[j] > 0.0) {
            const LobeTerm& t = m.terms[j];
            pdf += w[j] * kLobeFamilies[t.family].folded_pdf(m.params + t.offset, wo, wi);
        }
    return pdf;
}

// f_r per channel (no cosine) for wi and wo above the horizon: the sum of the lobes.
inline void lobe_mixture_eval(const LobeMixtureView& m, const Vec3& wi, const Vec3& wo, double out[3]) {
    const Geometry<double> g = make_geometry(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z);
    out[0] = out[1] = out[2] = 0.0;
    for (std::size_t j = 0; j < m.count; ++j) {
        const LobeTerm& t = m.terms[j];
        double v[3];
        kLobeFamilies[t.family].eval(g, m.params + t.offset, v);
        for (int c = 0; c < 3; ++c) out[c] += v[c];
    }
}

// The density lobe_mixture_sample draws from, per unit solid angle of wi, for wo and wi above the
// horizon.
inline double lobe_mixture_pdf(const LobeMixtureView& m, const Vec3& wo, const Vec3& wi) {
    double w[kMaxLobeTerms];
    if (!lobe_mixture_weights(m, wo, w)) return lobes::sampling::cosine_pdf(wi);
    return lobe_mixture_density(m, w, wo, wi);
}

// A draw for wo above the horizon and u1, u2 in [0, 1): u1 picks the lobe, then drives its sampler
// with u2; pdf is lobe_mixture_pdf at the drawn wi, 0 where the draw failed.
inline LobeMixtureDraw lobe_mixture_sample(const LobeMixtureView& m, const Vec3& wo, double u1, double u2) {
    double w[kMaxLobeTerms];
    Vec3 wi;
    double pdf;
    if (!lobe_mixture_weights(m, wo, w)) {
        wi = lobes::sampling::cosine(u1, u2);
        pdf = lobes::sampling::cosine_pdf(wi);
    } else {
        const LobeChoice c = choose_lobe(w, 1, m.count, u1);
        const LobeTerm& t = m.terms[c.lobe];
        const Vec3 d = kLobeFamilies[t.family].sample(m.params + t.offset, wo, c.v, u2);
        wi = {d.x, d.y, std::fabs(d.z)};
        pdf = lobe_mixture_density(m, w, wo, wi);
    }
    if (!(wi.z > 0.0 && std::isfinite(pdf) && pdf > 0.0)) return {{}, 0.0};
    return {wi, pdf};
}

}  // namespace brdfz::runtime::kernels
