#include "brdfz/sample/lobes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "brdfz/repr/analytic/catalogue.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/runtime/kernels/lobe_mixture.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"

namespace brdfz {
namespace {

namespace rk = runtime::kernels;
using lobes::sampling::cosine;
using lobes::sampling::cosine_pdf;
constexpr double kPi = std::numbers::pi;

// The lane loops of a family's sampler (LobeSampler::sample_n, add_folded_n), its code inlined.
template <typename F>
void sample_lanes(const double* p, const Vec3* wo, const double* u1, const double* u2, std::size_t n, Vec3* out) {
    for (std::size_t k = 0; k < n; ++k) out[k] = F::sample(p, wo[k], u1[k], u2[k]);
}
template <typename F>
void add_folded_lanes(const double* p, const Vec3* wo, const Vec3* wi, const double* w, std::size_t n, double* pdf) {
    for (std::size_t k = 0; k < n; ++k) {
        const double d = lobes::folded_pdf<F>(p, wo[k], wi[k]);
        pdf[k] += w[k] > 0.0 ? w[k] * d : 0.0;
    }
}

// Every family's sample and pdf (its header's), in the catalogue's order.
template <typename... Families>
constexpr std::array<LobeSampler, sizeof...(Families)> samplers_of(LobeList<Families...>) {
    return {LobeSampler{&Families::sample, &Families::pdf, &sample_lanes<Families>, &add_folded_lanes<Families>}...};
}
constexpr auto kSamplers = samplers_of(AllLobes{});

double mean(const double v[3]) { return (v[0] + v[1] + v[2]) / 3.0; }

// A family's position in the catalogue: its runtime family id.
int family_id(const LobeType& type) { return static_cast<int>(&type - lobe_types().data()); }

}  // namespace

const LobeSampler& lobe_sampler(const LobeType& type) { return kSamplers[family_id(type)]; }

LobeMixture::LobeMixture(const Model& model, std::span<const double> params, bool albedo)
    : params_(params.begin(), params.end()) {
    for (const Model::Term& t : model.terms()) terms_.push_back({family_id(*t.type), t.offset});
    if (!albedo) {
        albedo_.assign(kAlbedoNodes * terms_.size(), 0.0);
        return;
    }
    // Albedo of each lobe at each node, estimated with its own sampler over a fixed stratified set of
    // (u1, u2), with wo's azimuth varied too (anisotropic lobes): deterministic and cheap.
    const std::size_t n = terms_.size();
    albedo_.assign(kAlbedoNodes * n, 0.0);
    constexpr int kSide = 16;
    static_assert(kSide * kSide == kAlbedoSamples);
    for (int k = 0; k < kAlbedoNodes; ++k) {
        const double cos_o = (k + 0.5) / kAlbedoNodes, sin_o = std::sqrt(1.0 - cos_o * cos_o);
        for (std::size_t j = 0; j < n; ++j) {
            const rk::LobeFamily& family = rk::kLobeFamilies[terms_[j].family];
            const double* p = params_.data() + terms_[j].offset;
            double sum = 0.0;
            for (int i = 0; i < kAlbedoSamples; ++i) {
                const double phi_o = 2.0 * kPi * std::fmod(i * 0.6180339887498949, 1.0);
                const Vec3 wo{sin_o * std::cos(phi_o), sin_o * std::sin(phi_o), cos_o};
                Vec3 wi = family.sample(p, wo, (i % kSide + 0.5) / kSide, (i / kSide + 0.5) / kSide);
                wi.z = std::fabs(wi.z);
                const double pdf = family.folded_pdf(p, wo, wi);
                if (!(wi.z > 0.0 && pdf > 0.0)) continue;
                double f[3];
                family.eval(make_geometry(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z), p, f);
                sum += mean(f) * wi.z / pdf;
            }
            const double a = sum / kAlbedoSamples;
            albedo_[k * n + j] = std::isfinite(a) && a > 0.0 ? a : 0.0;
        }
    }
}

std::vector<double> LobeMixture::weights(const Vec3& wo) const {
    std::vector<double> w(terms_.size());
    rk::lobe_mixture_weights(view(), wo, w.data());
    return w;
}

double LobeMixture::pdf(const Vec3& wo, const Vec3& wi) const { return rk::lobe_mixture_pdf(view(), wo, wi); }

BrdfSample LobeMixture::sample(const Vec3& wo, double u1, double u2) const {
    const rk::LobeMixtureDraw d = rk::lobe_mixture_sample(view(), wo, u1, u2);
    return d.pdf > 0.0 ? BrdfSample{d.wi, d.pdf, {}} : BrdfSample{};
}

void LobeMixture::sample_block(const Vec3* wo, const std::array<double, 2>* u, std::size_t n, BrdfSample* out) const {
    constexpr std::size_t kBlock = 64;
    const std::size_t terms = terms_.size();
    double w[Model::kMaxTerms][kBlock], total[kBlock], v[kBlock], u2[kBlock], pdf[kBlock];
    Vec3 wi[kBlock], lane_wo[kBlock], lane_wi[kBlock];
    int chosen[kBlock];
    std::size_t lanes[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        const Vec3* o = wo + start;
        // The lobe weights, as lobe_mixture_weights() forms them for each lane.
        for (std::size_t k = 0; k < m; ++k) total[k] = 0.0;
        for (std::size_t j = 0; j < terms; ++j)
            for (std::size_t k = 0; k < m; ++k) {
                w[j][k] = rk::lobe_albedo(albedo_.data(), terms, j, rk::albedo_nodes(o[k].z));
                total[k] += w[j][k];
            }
        for (std::size_t j = 0; j < terms; ++j)
            for (std::size_t k = 0; k < m; ++k) w[j][k] = total[k] > 0.0 ? w[j][k] / total[k] : 0.0;
        // The choices (lobe_mixture_sample's); a model black at wo (every weight 0) is sampled with the
        // cosine density.
        for (std::size_t k = 0; k < m; ++k) {
            const double u1 = u[start + k][0];
            u2[k] = u[start + k][1];
            if (!(total[k] > 0.0)) {
                chosen[k] = -1;
                wi[k] = cosine(u1, u2[k]);
                continue;
            }
            const rk::LobeChoice c = rk::choose_lobe(&w[0][k], kBlock, terms, u1);
            chosen[k] = static_cast<int>(c.lobe);
            v[k] = c.v;
        }
        // Each lobe's draws together, then the mixture's density a lobe at a time across the block.
        for (std::size_t j = 0; j < terms; ++j) {
            std::size_t count = 0;
            double lane_v[kBlock], lane_u2[kBlock];
            for (std::size_t k = 0; k < m; ++k)
                if (chosen[k] == static_cast<int>(j)) lanes[count] = k, lane_wo[count] = o[k], lane_v[count] = v[k], lane_u2[count++] = u2[k];
            kSamplers[terms_[j].family].sample_n(params_.data() + terms_[j].offset, lane_wo, lane_v, lane_u2, count,
                                                 lane_wi);
            for (std::size_t c = 0; c < count; ++c) wi[lanes[c]] = {lane_wi[c].x, lane_wi[c].y, std::fabs(lane_wi[c].z)};
        }
        for (std::size_t k = 0; k < m; ++k) pdf[k] = chosen[k] < 0 ? cosine_pdf(wi[k]) : 0.0;
        for (std::size_t j = 0; j < terms; ++j)
            kSamplers[terms_[j].family].add_folded_n(params_.data() + terms_[j].offset, o, wi, w[j], m, pdf);
        for (std::size_t k = 0; k < m; ++k) {
            const double p = pdf[k];
            out[start + k] = wi[k].z > 0.0 && std::isfinite(p) && p > 0.0 ? BrdfSample{wi[k], p, {}} : BrdfSample{};
        }
    }
}

}  // namespace brdfz
