// brdfz::Brdf — the one interface every measured or compressed BRDF implements.
//
// Conventions (every representation, reader, writer, metric and sampler follows these):
//  - Local frame: the surface normal is +z. Both `wi` and `wo` point AWAY from the surface and are
//    unit vectors. `wi` is the incident (light) direction, `wo` the outgoing (view) direction.
//  - `eval(wi, wo)` returns f_r in 1/sr, with NO cosine. `eval_cos(wi, wo)` returns f_r · cosθi.
//    (pbrt's BxDF::f returns f; Mitsuba, powitacq and Falcor return f·cos: adapters say which.)
//  - Below the horizon (wi.z <= 0 or wo.z <= 0) eval returns 0; never NaN, for any input.
//  - Polar angles come from elevation() in frame.h (2·asin(½‖v − ẑ‖)), not acos(z).
//  - Colour: three channels, linear RGB. Monochrome data has channels() == 1 and repeats its value
//    in all three channels, so callers never branch on the channel count.
//  - Sampling (added with the samplers): sample(wo, u) → {wi, pdf, weight = f·cosθi/pdf};
//    pdf(wo, wi) is per unit solid angle of wi.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>

#include "brdfz/frame.h"

namespace brdfz {

using Rgb = std::array<double, 3>;

class Brdf {
public:
    virtual ~Brdf() = default;

    // f_r for one direction pair.
    Rgb eval(const Vec3& wi, const Vec3& wo) const {
        if (!(wi.z > 0.0 && wo.z > 0.0)) return {0.0, 0.0, 0.0};
        return eval_above(wi, wo);
    }
    // f_r · cosθi for one direction pair.
    Rgb eval_cos(const Vec3& wi, const Vec3& wo) const;

    // Batches: wi[k], wo[k] -> out[k]. The three spans must have equal length (ValueError otherwise).
    // No allocation per call; representations override the batch kernel for speed.
    void eval(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const;
    void eval_cos(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const;

    // 1 (monochrome) or 3 (RGB).
    virtual int channels() const = 0;
    // Exact size in bytes of the parameters the representation stores (not of the C++ object).
    virtual std::size_t nbytes() const = 0;
    // One line saying what this is, e.g. "tabular 90x90x180 float32 (linear lookup)".
    virtual std::string describe() const = 0;

protected:
    // f_r for a pair already known to be above the horizon (wi.z > 0 and wo.z > 0).
    virtual Rgb eval_above(const Vec3& wi, const Vec3& wo) const = 0;
    // Batch kernel over n pairs; must write 0 for below-horizon pairs. The default loops over eval().
    virtual void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const;
};

}  // namespace brdfz
