// Importance sampling of analytic models (repr/analytic/model.h): one sampler per lobe family, mixed
// in proportion to each lobe's directional albedo at wo. The mixture's single calls are brdfz::runtime's
// kernels (brdfz/runtime/kernels/lobe_mixture.h, which describes the mixture); this class builds the
// albedo table they read and runs the batch kernel, which shares their pieces.
//
// Each family samples with its header's sample and pdf (brdfz/runtime/kernels/lobes/*.h):
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
// The albedo table is estimated with each lobe's own sampler when the mixture is built, so the choice
// is deterministic and the pdf is exactly the density sample() draws from.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/repr/analytic/lobe.h"
#include "brdfz/runtime/kernels/lobe_mixture.h"

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
    static constexpr int kAlbedoNodes = runtime::kernels::kAlbedoNodes;  // cosθo nodes of the albedo table
    static constexpr int kAlbedoSamples = 256;  // sampled directions per node and lobe

    // Params must fit the model (as AnalyticBrdf validates them). Without `albedo` the table is left 0,
    // so the mixture samples cosθi/π: for a model that another sampler samples (AnalyticBrdf with a
    // compact sampler), whose loading then skips the estimate.
    LobeMixture(const Model& model, std::span<const double> params, bool albedo = true);

    // For wo above the horizon and u in [0, 1)²: wi and its pdf (pdf 0 for a failed draw); the runtime's
    // lobe_mixture_sample.
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // sample() for n draws (wo finite and above the horizon, u in [0, 1)², as sample() asks), in passes
    // over blocks: the lobe weights, the choices, each lobe's draws together, then the mixture's pdf a
    // lobe at a time across the block. The same operations as sample() lane by lane (the runtime
    // kernel's pieces), so the two agree to the bit.
    void sample_block(const Vec3* wo, const std::array<double, 2>* u, std::size_t n, BrdfSample* out) const;
    // Density of sample() at wi, for wo and wi above the horizon (lobe_mixture_pdf).
    double pdf(const Vec3& wo, const Vec3& wi) const;
    // Probability of choosing each lobe at wo; all 0 when the model is black there (cosine sampling).
    std::vector<double> weights(const Vec3& wo) const;
    // The albedo table the lobe weights interpolate: kAlbedoNodes × terms, node-major (node k at
    // cosθo = (k + ½) / kAlbedoNodes), for ports of the sampler.
    const std::vector<double>& albedo_table() const { return albedo_; }
    // The model, its parameters and this table as the runtime's kernels read them (valid while this
    // mixture lives).
    runtime::kernels::LobeMixtureView view() const { return {terms_.data(), terms_.size(), params_.data(), albedo_.data()}; }

private:
    std::vector<runtime::kernels::LobeTerm> terms_;
    std::vector<double> params_;
    std::vector<double> albedo_;  // kAlbedoNodes × terms, node-major
};

}  // namespace brdfz
