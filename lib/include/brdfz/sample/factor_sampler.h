// Importance sampling of a factored BRDF from its factors (after Lawrence et al. 2004), with an exact
// pdf. No evaluation grid of the BRDF: it is built from the factors on a (θh rows × 16 φh) grid per view
// slice, so it builds much faster than the half-vector sampler.
//
// The half vector h is drawn relative to wo in two steps:
//  1. θh from a density per view slice θo_k, piecewise linear in s = sin²(θh/2) (uniform in s is uniform
//     in solid angle, dωh = 2 ds dφ) between the factor's θh row edges, so continuous. Two choices
//     (FactorDensity): Marginal (default), the φh-marginal of the reconstruction's integrand
//     f·cosθi·(wo·h) at each row edge, through the factors (u_j at the row, v_j at the columns that
//     (θh, φh, θo) reach, the colour weights and the space's inverse); or Mixture, Lawrence's: each term
//     T_j = a_j·u_j·v_j gives the density |u_j(θh)| (layout hd_p: averaged over θd), mixed with weights
//     W_j(θo) = ∫ |T_j| cosθi dωi. A given wo mixes its two neighbouring slices linearly in θo. The
//     CDF is truncated at θmax = π/4 + θo/2, beyond which no azimuth reflects wo above the horizon.
//  2. φh ∝ wi.z = A + B·cosφh (A = cosθo·cos2θh, B = sinθo·sin2θh) over the azimuths where wi.z > 0,
//     by Newton's method on its closed-form CDF: the horizon is handled by construction, not by
//     rejection, and the density vanishes towards it as f·cosθi does.
// pdf(wo, wi) = Σ_slices w·q(s)/Q(s_max) · wi.z/norm(θh) / 2 / (4 wo·h) is exact. A small floor (uniform
// in s) keeps every row reachable, and a share of cosine-weighted sampling keeps the pdf positive
// wherever f·cosθi may be.
//
// Any factors, in any space, give a valid density (negative reconstructions count as 0, as eval clamps
// them). Against the half-vector sampler the Marginal density does as well in the log and cbrt spaces
// as in the linear ones (bench/factor_sample), so there is no per-space fallback.
#pragma once

#include <vector>

#include "brdfz/brdf.h"

namespace brdfz {

struct Factors;  // repr/factored.h, which holds this sampler

// The θh density of a slice (see above). Marginal follows the columns' factors, the Jacobian and the
// cosine; Mixture only the rows' factors, and its variance is far higher where the factors' shape is
// not f's (the log and cbrt spaces).
enum class FactorDensity { Mixture, Marginal };

struct FactorSamplerOptions {
    FactorDensity density = FactorDensity::Marginal;
    int n_theta_o = 16;         // view-elevation slices over [0°, kMaxThetaODeg]
    int n_phi = 16;             // points over φh ∈ [0, π] per θh row edge (Marginal) or row (Mixture weights)
    double cosine_share = 0.05; // probability of a cosine-weighted sample (as HalfVectorSamplerOptions)
    double floor = 1e-3;        // share of each slice's θh distribution spread uniformly over s
};

class FactorSampler {
public:
    static constexpr double kMaxThetaODeg = 89.5;

    // ValueError for options out of range.
    explicit FactorSampler(const Factors& factors, const FactorSamplerOptions& options = {});

    // For wo above the horizon and u in [0, 1)²: wi and its pdf (pdf 0 for a failed draw).
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // Density of sample() at wi, per unit solid angle, for wo and wi above the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;

    std::size_t nbytes() const;

private:
    struct SlicePair {
        int k0, k1;
        double t;  // weight of k1
    };
    SlicePair slices_for(const Vec3& wo) const;
    // The row holding s = sin²(θh/2).
    int row_of(double s) const;
    // CDF and density (per unit s) of slice k at s in row r.
    double cdf_at(int k, int r, double s) const;
    double density_at(int k, int r, double s) const;
    // Density of the data part per unit solid angle of h at s in row r (s < s_max, the truncation in row
    // r_max), for the slice pair, with wi.z and the azimuth normaliser at s.
    double half_density(const SlicePair& sp, int r, double s, int r_max, double s_max, double wi_z,
                        double norm) const;

    FactorSamplerOptions options_;
    int rows_ = 0;
    std::vector<double> s_edges_;  // rows + 1: s at the θh row edges, 0 … ½
    std::vector<double> theta_o_;  // slice elevations
    std::vector<double> cdf_;      // slices × (rows + 1), each 0 … 1
    std::vector<double> density_;  // slices × (rows + 1): density per unit s at the row edges
};

}  // namespace brdfz
