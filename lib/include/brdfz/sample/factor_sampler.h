// Importance sampling of a factored BRDF from its factors' CDFs (after Lawrence et al. 2004), with an
// exact pdf. No evaluation grid: it is built from the factors alone.
//
// A factorisation writes the BRDF as a sum of terms T_j = a_j·u_j(θh[, θd])·v_j(columns) (a_j: the
// term's colour weight, averaged over channels). Term j gives a density over the half vector h,
//   p_j(h) ∝ |u_j(θh)|      (θh rows; layout hd_p averages its rows over θd),
// and for a view elevation θo the terms are mixed with weights W_j(θo) = ∫ |T_j| cosθi dωi, each term's
// share of the albedo (estimated by a small quadrature over h from the factors). The mixture is summed
// at build time into one θh density per θo slice, piecewise linear in s = sin²(θh/2) (uniform in s is
// uniform in solid angle) between the factor's θh row edges, so continuous; a given wo mixes its two
// neighbouring slices linearly in θo: the Lawrence mixture Σ_j P(j|wo)·p_j(h), one CDF search instead
// of two.
//
// The horizon is handled by construction, not by rejection: φh (relative to wo) is uniform, and θh is
// drawn from the slice's CDF truncated at θlim(φh) = π/4 + ½·atan2(sinθo·cosφh, cosθo), the largest θh
// whose mirror direction wi is above the horizon. The truncated density is renormalised by the CDF at
// θlim, so pdf(wo, wi) = Σ_slices w·q(s)/Q(s_lim) / (2π·2) / (4 wo·h) is exact and every data draw lands
// above the horizon. A small floor (uniform in s) keeps Q(s_lim) > 0, and a share of cosine-weighted
// sampling keeps the pdf positive wherever f·cosθi may be.
//
// Any factors give a valid density (magnitudes are used); how well it matches f depends on the space:
// factored.h's FactoredBrdf uses this sampler for linear and cos spaces and the half-vector sampler
// for log and cbrt (measured in bench/README.md, "Factor sampler").
#pragma once

#include <vector>

#include "brdfz/brdf.h"

namespace brdfz {

struct Factors;  // repr/factored.h, which holds this sampler

// The θh density of a slice: Mixture, Lawrence's per-term densities |u_j| mixed by the terms' albedo
// shares; Marginal, the φh-marginal of the reconstruction's integrand f·cosθi·(wo·h) at the row edges
// (n_phi points each), which also follows the columns' factors, the Jacobian and the cosine.
enum class FactorDensity { Mixture, Marginal };

struct FactorSamplerOptions {
    FactorDensity density = FactorDensity::Marginal;
    int n_theta_o = 16;         // view-elevation slices of term weights over [0°, kMaxThetaODeg]
    int n_phi = 16;             // quadrature points over φh ∈ [0, π] per θh row, for the term weights
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
