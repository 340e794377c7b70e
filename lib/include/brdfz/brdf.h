// brdfz::Brdf — the one interface every measured or compressed BRDF implements.
//
// Conventions (every representation, reader, writer, metric and sampler follows these):
//  - Local frame: the surface normal is +z. Both `wi` and `wo` point AWAY from the surface. `wi` is the
//    incident (light) direction, `wo` the outgoing (view) direction. Every call takes them as
//    prepare_direction (runtime/vec.h) makes them: unit vectors as they are, others normalised; a NaN,
//    infinite or zero direction gives 0 (eval, pdf) or a failed draw.
//  - `eval(wi, wo)` returns f_r in 1/sr, with NO cosine. `eval_cos(wi, wo)` returns f_r · cosθi.
//    (pbrt's BxDF::f returns f; Mitsuba, powitacq and Falcor return f·cos: adapters say which.)
//  - Below the horizon (wi.z <= 0 or wo.z <= 0) eval returns 0; never NaN, for any input.
//  - Polar angles come from elevation() in frame.h (2·asin(½‖v − ẑ‖)), not acos(z).
//  - Colour: three channels, linear RGB. Monochrome data has channels() == 1 and repeats its value
//    in all three channels, so callers never branch on the channel count.
//  - Sampling: sample(wo, u1, u2) → {wi, pdf, weight = f·cosθi/pdf}; pdf(wo, wi) is per unit solid
//    angle of wi and equals the density sample() draws from. A failed sample (wo below the horizon,
//    u outside [0, 1), a direction drawn below the horizon) has pdf 0 and weight 0. Representations
//    without a sampler of their own use cosine-weighted hemisphere sampling.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <numbers>
#include <span>
#include <string>

#include "brdfz/frame.h"

// The protected hooks of a representation with its own kernels (one pair and batches of eval and
// sample, and pdf), declared in its class by this one line; Brdf below says what each must do.
#define BRDFZ_BRDF_KERNELS                                                                                        \
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;                                               \
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;                     \
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override;                                \
    void sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const override; \
    double pdf_above(const Vec3& wo, const Vec3& wi) const override

namespace brdfz {

struct GridSpec;
class Table;

using Rgb = std::array<double, 3>;

struct BrdfSample {
    Vec3 wi;
    double pdf = 0;  // per unit solid angle of wi; 0 marks a failed sample
    Rgb weight{};    // f(wi, wo)·cosθi / pdf; 0 for a failed sample
};

class Brdf {
public:
    virtual ~Brdf() = default;

    // f_r for one direction pair.
    Rgb eval(const Vec3& wi, const Vec3& wo) const {
        Vec3 a = wi, b = wo;
        if (!prepare_direction(a) || !prepare_direction(b) || !(a.z > 0.0 && b.z > 0.0)) return {0.0, 0.0, 0.0};
        return eval_above(a, b);
    }
    // f_r · cosθi for one direction pair.
    Rgb eval_cos(const Vec3& wi, const Vec3& wo) const;

    // Batches: wi[k], wo[k] -> out[k]. The three spans must have equal length (ValueError otherwise).
    // No allocation per call; representations override the batch kernel for speed.
    void eval(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const;
    void eval_cos(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const;

    // Draw wi for a given wo from u1, u2 in [0, 1).
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // Density of sample(wo, ·) at wi, per unit solid angle; 0 below the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;
    // Batches: out[k] = sample(wo[k], u[k][0], u[k][1]) / pdf(wo[k], wi[k]); equal lengths or ValueError.
    void sample(std::span<const Vec3> wo, std::span<const std::array<double, 2>> u, std::span<BrdfSample> out) const;
    void pdf(std::span<const Vec3> wo, std::span<const Vec3> wi, std::span<double> out) const;
    // The batch sample evaluates the weights with the batch eval kernel, or with a kernel fusing draw and
    // weight (sample_batch). sample()'s rules, which such kernels follow too: the inputs it draws for (wo
    // above the horizon, u in [0, 1)²) and the draws it keeps (wi above the horizon, pdf positive and finite).
    static bool can_draw(const Vec3& wo, double u1, double u2) {
        return wo.z > 0.0 && u1 >= 0.0 && u1 < 1.0 && u2 >= 0.0 && u2 < 1.0;
    }
    static bool usable(const BrdfSample& s) {
        return s.wi.z > 0.0 && s.pdf > 0.0 && s.pdf < std::numeric_limits<double>::infinity();
    }

    // 1 (monochrome) or 3 (RGB).
    virtual int channels() const = 0;
    // Exact size in bytes of the parameters the representation stores (not of the C++ object).
    virtual std::size_t nbytes() const = 0;
    // One line saying what this is, e.g. "tabular 90x90x180 float32 (linear lookup)".
    virtual std::string describe() const = 0;
    // The largest elevation (radians) of the incident direction wi up to which the values are data
    // rather than extrapolation: tabulate() extrapolates beyond it by clamping the incident elevation,
    // and compare() does not count pairs beyond it (over the grid, whose bins stand for both (wi, wo)
    // and (wo, wi), neither θi nor θo beyond it), so the source's own extrapolation neither shapes a
    // compressed representation nor judges it. π/2 (everywhere) unless the source knows better (RGL
    // files pad their θi range: formats/rgl.h).
    virtual double measured_theta_max() const { return std::numbers::pi / 2; }
    // True when eval(wi, wo) == eval(wo, wi) by construction (a table whose grid folds φd by
    // reciprocity), so that tabulating onto a reciprocal grid needs one side of each pair. False unless
    // a representation knows better; measured data are not exactly reciprocal (RGL files).
    virtual bool reciprocal() const { return false; }
    // True when eval(wi, wo) equals eval at their mirror images y → −y by construction (a table whose
    // grid folds φd by the mirror, table.h's Symmetry::Bilateral), so that tabulating onto such a grid
    // needs one of the two. False unless a representation knows better.
    virtual bool bilateral() const { return false; }

    // The Rusinkiewicz grid a gridded representation is defined on (tables, compact tables,
    // factorisations, PCA), for callers that sample a BRDF on its own grid; nullptr otherwise.
    virtual const GridSpec* grid() const { return nullptr; }
    // The float32 table when the representation stores one as it is (TabularBrdf): its bins and
    // validity are read directly instead of evaluated; nullptr otherwise.
    virtual const Table* stored_table() const { return nullptr; }

protected:
    // f_r for a pair already known to be above the horizon (wi.z > 0 and wo.z > 0).
    virtual Rgb eval_above(const Vec3& wi, const Vec3& wo) const = 0;
    // Batch kernel over n pairs; must write 0 for below-horizon pairs. The default loops over eval().
    virtual void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const;
    // Sampler for wo above the horizon and u in [0, 1)²: returns wi and its pdf; sample() fills in
    // the weight (overrides may set it when they have f at hand) and rejects wi below the horizon.
    // The default draws cosθi/π.
    virtual BrdfSample sample_above(const Vec3& wo, double u1, double u2) const;
    // Density for wo and wi above the horizon, consistent with sample_above. Default cosθi/π.
    virtual double pdf_above(const Vec3& wo, const Vec3& wi) const;
    // Batch kernel of sample(span) over n draws, each as sample(wo[k], u[k][0], u[k][1]) gives it. The
    // default draws blocks with sample_above and evaluates the weights they need with eval_batch;
    // overrides fuse the two (TabularBrdf: the lookup from the draw's own angles).
    virtual void sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const;
    // Batch kernel of pdf(span): out[k] = pdf(wo[k], wi[k]), 0 below the horizon. The default loops over pdf().
    virtual void pdf_batch(const Vec3* wo, const Vec3* wi, double* out, std::size_t n) const;

private:
    // sample() without the weight when the sampler left it unset: a failed draw is returned as {}.
    BrdfSample draw(const Vec3& wo, double u1, double u2) const;
};

}  // namespace brdfz
