// Importance sampling of analytic models (repr/analytic/model.h): one sampler per lobe family, mixed
// in proportion to each lobe's directional albedo at wo.
//
// Each family samples with its header's sample and pdf (repr/analytic/*.h):
//   lambert                       cosine-weighted hemisphere
//   ggx*, ggx_aniso               visible normals (Heitz 2018; drawn by Dupuy & Benyoub's spherical caps, 2023)
//   beckmann*                     visible normals (Heitz & d'Eon 2014): slopes by inverting their CDFs
//   blinn_phong, ward             half vector from D(h)·cosθh, reflected about it
//   ashikhmin_shirley             its own anisotropic half-vector density, or cosine for its diffuse part
//   lafortune                     cosine-power lobe around its axis (cxy·wo.x, cxy·wo.y, cz·wo.z)
// Each draws a direction on the whole sphere with a density that integrates to 1 there. A draw below
// the horizon is folded back (z → −z), so the density over the upper hemisphere is
// p(w) + p(w with −z): it integrates to exactly 1 and no sample is lost. Half-vector samplers fold
// the same way in h: an h facing away from wo (wo·h ≤ 0) is turned half a revolution about the normal,
// which faces it toward wo and leaves an isotropic density unchanged.
//
// The mixture picks a lobe with probability ∝ its directional albedo (mean over channels) at wo,
// read from a table over cosθo that each lobe's own sampler estimates when the mixture is built, so
// the choice is deterministic and the pdf is exactly the density sample() draws from. A model that is
// black at wo (every albedo 0) is sampled with the cosine density.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/repr/analytic/lobe.h"

namespace brdfz {

class Model;

// A family's sampler at run time (as LobeType is its eval).
struct LobeSampler {
    // The family's sample and pdf (lobe.h): a direction on the unit sphere (possibly below the horizon)
    // for wo above the horizon and u1, u2 in [0, 1), and its density there; params are the lobe's own.
    Vec3 (*sample)(const double* params, const Vec3& wo, double u1, double u2);
    double (*pdf)(const double* params, const Vec3& wo, const Vec3& w);
    // The same over n lanes, in loops that inline them (and vectorise where the family's code does):
    // out[k] = sample(params, wo[k], u1[k], u2[k]); and pdf[k] += w[k]·(density at wi[k] and at wi[k]
    // mirrored in z), the folded density weighted, for the lanes with w[k] > 0.
    void (*sample_n)(const double* params, const Vec3* wo, const double* u1, const double* u2, std::size_t n,
                     Vec3* out);
    void (*add_folded_n)(const double* params, const Vec3* wo, const Vec3* wi, const double* w, std::size_t n,
                         double* pdf);
};

// The sampler of a family in the catalogue (catalogue.h); every family has one.
const LobeSampler& lobe_sampler(const LobeType& type);

class LobeMixture {
public:
    static constexpr int kAlbedoNodes = 16;     // cosθo nodes of the albedo table
    static constexpr int kAlbedoSamples = 256;  // sampled directions per node and lobe

    // Params must fit the model (as AnalyticBrdf validates them).
    LobeMixture(const Model& model, std::span<const double> params);

    // For wo above the horizon and u in [0, 1)²: wi and its pdf (pdf 0 for a failed draw).
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // sample() for n draws (wo finite and above the horizon, u in [0, 1)², as sample() asks), in passes
    // over blocks: the lobe weights, the choices, each lobe's draws together, then the mixture's pdf a
    // lobe at a time across the block. sample() is this kernel on one draw, so the two agree to the bit.
    void sample_block(const Vec3* wo, const std::array<double, 2>* u, std::size_t n, BrdfSample* out) const;
    // Density of sample() at wi, for wo and wi above the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;
    // Probability of choosing each lobe at wo; all 0 when the model is black there (cosine sampling).
    std::vector<double> weights(const Vec3& wo) const;
    // The albedo table lobe_weights() interpolates: kAlbedoNodes × terms, node-major (node k at
    // cosθo = (k + ½) / kAlbedoNodes), for ports of the sampler.
    const std::vector<double>& albedo_table() const { return albedo_; }

private:
    struct Term {
        const LobeType* type;
        LobeSampler sampler;
        std::size_t offset;  // of its parameters in params_
    };
    // Lobe probabilities at wo into w[0..terms); false when the model is black there.
    bool lobe_weights(const Vec3& wo, double* w) const;
    // Term t's density folded onto the upper hemisphere.
    double folded_density(const Term& t, const Vec3& wo, const Vec3& wi) const;

    std::vector<Term> terms_;
    std::vector<double> params_;
    std::vector<double> albedo_;  // kAlbedoNodes × terms, node-major
};

}  // namespace brdfz
