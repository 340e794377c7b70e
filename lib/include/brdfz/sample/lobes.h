// Importance sampling of analytic models (repr/analytic/model.h): one sampler per lobe family, mixed
// in proportion to each lobe's directional albedo at wo.
//
// Per-family samplers (lib/src/sample/lobes.cpp):
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

#include <cstddef>
#include <span>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/repr/analytic/lobe.h"

namespace brdfz {

class Model;

struct LobeSampler {
    // A direction on the unit sphere (possibly below the horizon) for wo above the horizon and
    // u1, u2 in [0, 1); params are the lobe's own, in its family's order.
    Vec3 (*sample)(const double* params, const Vec3& wo, double u1, double u2);
    // Density of sample() at the unit vector w, per unit solid angle, over the whole sphere.
    double (*density)(const double* params, const Vec3& wo, const Vec3& w);
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
