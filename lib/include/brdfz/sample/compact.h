// The compact sampler of every gridded kind (tables, factorisations, PCA, φh stacks): its tables are
// built here from the BRDF's eval; draws and densities are the runtime's kernel
// (brdfz/runtime/kernels/compact_sampler.h, whose header says what the tables mean), so the library,
// brdfz::runtime and the exported shaders sample alike.
//
// Build: per view slice, the integrand per unit solid angle of the half vector,
//   g(h) = Y(f(wi, wo))·cosθi·4(wo·h),   wi = reflect(wo, h), Y the Rec. 709 luminance,
// whose integral over h is the directional albedo's luminance, so that a density ∝ g gives weights
// f·cosθi/pdf of constant luminance. The row edges (s = sin²(θh/2)) are quantiles of g's θh marginal,
// averaged over the slices and mixed with a share spread uniformly over √θh (MERL's axis), so that
// rows are narrow where the material's mass is (a specular peak) and still cover the hemisphere. Each
// cell's mass is g's integral over stratified points on both sides of wo's plane; each slice's edge
// weight is g's integral over φ at the edge, which shapes the density linearly across the row.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/runtime/kernels/compact_sampler.h"

namespace brdfz {

// The defaults keep the weights' variance low up to grazing views while the tables stay within 16 KiB.
struct CompactSamplerOptions {
    int slices = 12;              // view elevations, uniform in cosθo over [0°, kMaxThetaODeg], ≥ 2
    int rows = 32;                // s rows, ≥ 1
    int cols = 16;                // φ columns over [0, φmax], ≥ 1
    double cosine_share = 0.02;   // probability of a cosine-weighted draw, in (0, 1)
    double uniform_share = 0.5;   // share of the row placement spread uniformly over √θh, in [0, 1]
    int points = 2;               // stratified points per cell and axis (and side), 1-8
    int view_azimuths = 1;        // wo azimuths g is averaged over per slice (anisotropic data), 1-64
    int threads = 1;              // building; 0: one per hardware thread
};

class CompactSampler {
public:
    static constexpr double kMaxThetaODeg = 89.5;

    // The stored tables (formats/SPEC.md): the runtime kernel's view of them is view().
    struct Tables {
        int slices = 0, rows = 0, cols = 0;
        double cos_theta_max = 0, cosine_share = 0;
        std::vector<float> s_edges;
        std::vector<std::uint32_t> row_cdf;
        std::vector<std::uint16_t> col_cdf;
        std::vector<std::uint16_t> edge_weight;  // binary16
        bool operator==(const Tables&) const = default;
    };

    // Builds the tables from the BRDF's eval. ValueError for options out of range.
    explicit CompactSampler(const Brdf& brdf, const CompactSamplerOptions& options = {});
    // From stored tables; ValueError naming what is wrong (shapes, edges not increasing from 0 to ½,
    // CDFs not ending at full scale or decreasing, edge weights negative or not finite, parameters out of
    // range).
    explicit CompactSampler(Tables tables);

    const Tables& tables() const { return t_; }
    runtime::kernels::CompactSamplerView view() const;

    // For wo above the horizon and u in [0, 1)²: wi and its pdf, which is pdf(wo, wi) (0: failed).
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // Density of sample() at wi per unit solid angle, for wo and wi above the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;

    // Bytes of the tables: what a renderer holds beside the representation.
    std::size_t nbytes() const;

private:
    Tables t_;
};

}  // namespace brdfz
