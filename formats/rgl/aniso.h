// RGL files whose θi-dependent tables are also tabulated over φi (`phi_i` with two or more entries),
// evaluated, sampled and given pdfs the way Mitsuba 3's `measured` plugin does. Private to the reader.
//
// Layout (as Mitsuba reads it): vndf and luminance are [nφ, nθ, rows, cols], rgb [nφ, nθ, 3, rows, cols];
// every table is read at (φi, θi) by bilinear interpolation between the four neighbouring (φi, θi)
// slices, each parameter clamped to its tabulated range. With more than two φi entries the microfacet
// normal's azimuth in the vndf, ndf and rgb tables is absolute (φm), otherwise relative to φi as in
// isotropic files. ndf and sigma are single tables over (u_θ, u_φ) as before, sigma read at wi's own
// (u_θi, u_φi). When the φi entries span 2π/k for k = 2 or 4 (rint), the file stores one of k
// symmetric copies: both directions are first mapped into it, by a half turn (k = 2: x and y negated
// when y > 0) or by mirroring x and y onto their negative half-axes (k = 4).
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/formats/rgl.h"
#include "scalar_warp.h"

namespace brdfz::rgl::detail {

// The four (φi, θi) slices around a parameter point and their weights (summing to 1).
struct Corners {
    std::size_t slice[4] = {0, 0, 0, 0};
    double weight[4] = {1.0, 0.0, 0.0, 0.0};
};

// A point of [0,1]² and the density there.
// A density given by a bilinearly interpolated rows × cols table per slice, normalised per slice, with
// the CDFs that sample it (Mitsuba's Marginal2D with Continuous = true); tables of several slices are
// blended entry by entry before any nonlinear step, so the blended CDFs are those of the blended density.
class SliceWarp {
public:
    // ValueError (naming `what`) for a negative value or a slice that does not integrate to a
    // positive finite number.
    SliceWarp(const char* what, const std::vector<float>& data, std::size_t slices, std::size_t rows,
              std::size_t cols);
    WarpPoint sample(double ux, double uy, const Corners& c) const;  // u uniform on [0,1]²
    WarpPoint invert(double x, double y, const Corners& c) const;    // the inverse of sample()
    double eval(double x, double y, const Corners& c) const;

private:
    std::size_t rows_, cols_;
    std::vector<float> data_, cond_, marg_;  // normalised data; CDF along x per row; CDF along y
};

class Anisotropic {
public:
    // `t` outlives this object. ValueError unless phi_i holds >= 2 finite, strictly increasing values;
    // the grids' shapes are checked by RglBrdf.
    explicit Anisotropic(const Tensors& t);

    Rgb eval(const Vec3& wi, const Vec3& wo) const;             // f, wi the file's incident direction
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;  // as RglBrdf (rgl.h): warps follow wo
    double pdf(const Vec3& wo, const Vec3& wi) const;

private:
    Corners corners(double phi, double theta) const;

    const Tensors& t_;
    bool relative_azimuth_;  // two φi entries at most: φm is measured from φi
    int reduction_;          // 2 or 4: the φi range covers 2π/reduction; otherwise 1
    SliceWarp vndf_;
    std::optional<SliceWarp> luminance_;
};

}  // namespace brdfz::rgl::detail
