// RGL-EPFL measured materials (Dupuy & Jakob, "An Adaptive Parameterization for Efficient Material
// Acquisition and Rendering", SIGGRAPH Asia 2018; rgl.epfl.ch/materials): `.bsdf` tensor files.
// Isotropic RGB files only; anisotropic and spectral ones are reported as UnsupportedError.
//
// Evaluation reproduces Mitsuba 3's `measured` plugin (variant scalar_rgb), computed in double:
// the microfacet normal m = normalize(wi + wo) is mapped through the inverse of the VNDF warp
// conditioned on θi to a point of the RGB tables, whose value is scaled by ndf(m) / (4·sigma(wi))
// when the file's jacobian flag is set.
// Direction mapping: the file's incident direction (the θi its tables are conditioned on) is our
// `wi`, Mitsuba's `si.wi`. Mitsuba's eval returns f·cosθo; eval here returns f, that value / wo.z.
// Like Mitsuba, nothing is clamped: real files hold slightly negative RGB values, and eval returns
// slightly negative f_r where they dominate. Where the result would not be finite (a zero sigma,
// an empty VNDF row, f overflowing at wo.z → 0, a NaN or infinite direction), eval returns 0.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/table.h"

namespace brdfz::rgl {

namespace detail {
class Marginal2D;  // the VNDF warp, private to the reader (formats/rgl/marginal2d.h)
}

// `slices` tables of rows × cols float32 samples, row-major (column index fastest), as stored.
struct Grids {
    std::size_t slices = 1, rows = 0, cols = 0;
    std::vector<float> values;
};

// The tensors of an isotropic RGB file that evaluation uses, in the file's layout (storage form;
// RglBrdf builds its warps from them). Every grid spans [0,1]² in the parameterisation's unit
// coordinates: x = u_θ = sqrt(θ / (π/2)), y = u_φ = (φ + π) / 2π.
struct Tensors {
    std::vector<float> theta_i;  // incident elevations (radians) the θi-dependent grids are tabulated at
    Grids ndf;                   // 1 slice: microfacet distribution D(m), x = u_θm, y = u_φm (relative to φi)
    Grids sigma;                 // 1 slice: projected microfacet area σ(wi), x = u_θi, y = u_φi
    Grids vndf;                  // one slice per θi: visible normal density, x = u_θm, y = u_φm
    Grids rgb;                   // three slices per θi (R, G, B), over the VNDF warp's unit square
    bool jacobian = true;        // multiply by D(m) / (4·σ(wi)) (the file's `jacobian` flag)
};

class RglBrdf final : public Brdf {
public:
    // ValueError unless the shapes agree (grids at least 2×2, vndf with one slice and rgb with three
    // per θi, theta_i strictly increasing) and theta_i, ndf, sigma and vndf are finite with every
    // vndf slice integrating to a positive number. Non-finite rgb values are stored as 0.
    explicit RglBrdf(Tensors tensors);
    ~RglBrdf() override;
    RglBrdf(const RglBrdf&) = delete;
    RglBrdf& operator=(const RglBrdf&) = delete;

    const Tensors& tensors() const { return tensors_; }

    int channels() const override { return 3; }
    // Bytes of the float32 tensors kept (theta_i, ndf, sigma, vndf, rgb); the derived warp tables
    // are not counted.
    std::size_t nbytes() const override;
    std::string describe() const override;

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;

private:
    Rgb eval_one(const Vec3& wi, const Vec3& wo) const;

    Tensors tensors_;
    std::unique_ptr<const detail::Marginal2D> vndf_;
};

struct ReadResult {
    std::unique_ptr<RglBrdf> brdf;
    std::vector<std::size_t> dims;  // shape of the file's `rgb` tensor, e.g. {1, 8, 3, 32, 32}
    // Over the individual values of the `rgb` tensor (not grid points): valid (finite, >= 0),
    // negative, NaN, Inf. Negative values are kept as they are (Mitsuba does); NaN and Inf are
    // stored as 0. `clamped` stays 0. The file's `valid` bitmask is not used (Mitsuba ignores it).
    ValidityCounts counts;
    double min_value = 0, max_value = 0;  // range of the rgb tensor's finite values; 0, 0 if none
    std::string description;              // the file's `description` field
};

// Checks the whole field table (bounds, overflow, required fields and shapes) before reading any
// data. FormatError for an invalid file, UnsupportedError for a valid anisotropic or spectral one,
// IoError when the OS cannot read it; each names the file.
ReadResult read(const std::string& path);

}  // namespace brdfz::rgl
