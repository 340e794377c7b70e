// Data-driven importance sampling for any isotropic Brdf, with an exact pdf.
//
// For K view elevations θo_k, the integrand f(wi, wo_k)·cosθi, pulled back to half vectors, is
// tabulated as a piecewise-constant distribution (Piecewise2D) over x = |φh − φo| / π (isotropy makes
// it symmetric about the plane of wo) and y = √(θh / (π/2)), MERL's square-root axis, which puts
// cells where specular peaks are. A given wo picks one of its two neighbouring slices at random with
// linear weights in θo, draws h, and reflects wo about h. The pdf of wi is the blended slice density
// times the Jacobians (dωh = 2π² y sinθh dx dy over both signs of φ; dωi = 4 (wo·h) dωh), mixed with a
// small share of cosine-weighted sampling so that the pdf is positive wherever f·cos might be.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/sample/piecewise2d.h"

namespace brdfz {

struct HalfVectorSamplerOptions {
    int n_theta_o = 32;       // view-elevation slices over [0°, kMaxThetaODeg]
    int n_theta_h = 64;       // cells along y = √(θh / (π/2))
    int n_phi = 64;           // cells along |φh − φo| ∈ [0, π]
    // Probability of a cosine-weighted sample (defensive mixture). On sharp data it sets the albedo
    // estimate's variance floor, ≈ share/(1 − share)·ρ², so it is small; smaller still, the draws that
    // cover an environment's light away from the lobe grow too rare.
    double cosine_share = 0.05;
    int threads = 0;          // 0: one per hardware thread, for building
};

class HalfVectorSampler {
public:
    static constexpr double kMaxThetaODeg = 89.5;

    HalfVectorSampler(const Brdf& brdf, const HalfVectorSamplerOptions& options = {});
    // Movable, not copyable: the slices' views point into the sampler's own tables.
    HalfVectorSampler(HalfVectorSampler&&) = default;
    HalfVectorSampler& operator=(HalfVectorSampler&&) = default;
    HalfVectorSampler(const HalfVectorSampler&) = delete;
    HalfVectorSampler& operator=(const HalfVectorSampler&) = delete;

    // For wo above the horizon and u in [0, 1)²: wi and its pdf (pdf 0 when wi falls below the horizon).
    BrdfSample sample(const Vec3& wo, double u1, double u2) const { return draw(wo, u1, u2).sample; }

    // A draw with the angles it was made from, so that a representation looking f up by the pair's
    // half-vector angles gets them without recomputing them from wi and wo (detail/table_sample.h).
    // In wo's azimuthal frame wo = (sin_o, 0, cos_o) and h = (sin_h·cos_p, sin_h·sin_p, cos_h), with
    // φ = |φh − φo| drawn in [0, π] and sin_p carrying the side of wo's plane; wi = reflect(wo, h).
    struct Draw {
        BrdfSample sample;       // wi and pdf, the weight unset; pdf 0 when wi falls below the horizon
        bool half = false;       // drawn from the data's half-vector share: the angles below are set
        double sin_h = 0, cos_h = 0, sin_p = 0, cos_p = 0, sin_o = 0, cos_o = 0;
    };
    Draw draw(const Vec3& wo, double u1, double u2) const;

    // Up to kBlock draws at once, as arrays (the table kernel's passes read them so), each draw()'s bit
    // for bit: the same operations per draw, run across draws in vector registers (SSE2, or AVX2
    // without FMA contraction where the CPU has it: detail/simd.h). Inputs outside sample()'s domain
    // (Brdf::can_draw) give a failed draw, pdf 0. Large enough that the table kernel's memory reads of
    // many draws overlap; its arrays then take ~50 KB of stack.
    static constexpr std::size_t kBlock = 128;
    struct Draws {
        double wi_x[kBlock], wi_y[kBlock], wi_z[kBlock], pdf[kBlock];  // pdf 0: failed
        bool half[kBlock];
        double sin_h[kBlock], cos_h[kBlock], sin_p[kBlock], cos_p[kBlock], sin_o[kBlock], cos_o[kBlock];
    };
    void draw_block(const Vec3* wo, const std::array<double, 2>* u, std::size_t n, Draws& out) const;
    // Density of sample() at wi, per unit solid angle, for wo and wi above the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;

    std::size_t nbytes() const;

    // Read-only views of the tables, for ports of the sampler (the Python package's Mitsuba bridge):
    // the options, the slices' view elevations, and slice 0's view of the stacked distributions
    // (slice k is slices().stacked(k)).
    const HalfVectorSamplerOptions& options() const { return options_; }
    const std::vector<double>& theta_o() const { return theta_o_; }
    Piecewise2D::View slices() const { return first_; }

private:
    Piecewise2D::View slice(int k) const { return first_.stacked(k); }

    HalfVectorSamplerOptions options_;
    std::vector<double> theta_o_;
    // The slices' distributions, their tables end to end (Piecewise2D::View), so that draw_block's CDF
    // searches across draws gather from one base whichever slice each draw uses; first_ views slice 0.
    struct Stacked {
        std::vector<float> marginal, conditional, density;
        std::vector<std::uint32_t> marginal_guide, conditional_guide;
    } stacked_;
    Piecewise2D::View first_{};
};

}  // namespace brdfz
