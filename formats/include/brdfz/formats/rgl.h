// RGL-EPFL measured materials (Dupuy & Jakob, "An Adaptive Parameterization for Efficient Material
// Acquisition and Rendering", SIGGRAPH Asia 2018; rgl.epfl.ch/materials): `.bsdf` tensor files.
// RGB files, isotropic and anisotropic (phi_i with more than one entry; formats/rgl/aniso.h has the
// layout); spectral ones are reported as UnsupportedError.
//
// Evaluation reproduces Mitsuba 3's `measured` plugin (variant scalar_rgb), computed in double:
// the microfacet normal m = normalize(wi + wo) is mapped through the inverse of the VNDF warp
// conditioned on θi to a point of the RGB tables, whose value is scaled by ndf(m) / (4·sigma(wi))
// when the file's jacobian flag is set.
// Batch kernels (formats/rgl/kernels.cpp) evaluate, sample and give pdfs across pairs in SIMD registers
// (SSE2, AVX2 or AVX-512, the widest the CPU has; every build gives the same bits), one call at a time
// included. They take angles from a polynomial arctangent and a sine table rather than libm: f, pdf
// and sample weights are within 1e-8 (relative; for values below 1e-4 of a batch's largest, of that)
// and sampled directions within 1e-8 of the same arithmetic with libm's functions
// (tests/formats/rgl_kernel_test.cpp).
// Direction mapping: the file's incident direction (the θi its tables are conditioned on) is our
// `wi`, Mitsuba's `si.wi`. Mitsuba's eval returns f·cosθo; eval here returns f, that value / wo.z.
//
// Sampling follows Mitsuba's `measured` plugin: the luminance warp (conditioned on θ of the given
// direction) maps u to a point of the VNDF warp's square, the VNDF warp maps that to a microfacet
// normal m in unit coordinates u_m, and the given direction is reflected about m. The density is
// the product of the two warps' densities over the Jacobian dω/du_m = 2π²·u_θm·sinθm·4(w·m).
// Mitsuba draws its `wo` given `si.wi`; our API draws wi given wo, so the warps are conditioned on
// our wo as if it were the file's incident direction (the data are nearly reciprocal):
//     pdf(wo = A, wi = B) == Mitsuba's pdf(si.wi = A, wo = B),
// and sample(wo, u1, u2) reflects our wo where Mitsuba, given si.wi = wo and sample2 = (u1, u2),
// reflects si.wi. The weight is f(wi, wo)·cosθi / pdf with the true f (eval, wi incident), so
// estimates are unbiased wherever pdf > 0. Because the warps follow wo and f follows wi, a little
// of f·cosθi can lie where pdf = 0: on the RGL-EPFL files tried, none at θo <= 60°, < 1e-6 of the
// albedo at 80°, up to 0.08% at 87°, which estimates then miss. Two deliberate differences from
// Mitsuba keep pdf the exact density of what sample draws: the warps are inverted exactly in double
// (Mitsuba approximates nearly constant patches), and the Jacobian is not clamped below at 1e-6
// (Mitsuba's clamp lowers its pdf for m within ~2e-5 rad of the normal). Otherwise the two pdfs
// agree to Mitsuba's float32 precision (~1e-5, at worst ~1e-4 on the files tried).
// Normals that reflect wo below the horizon give failed samples (pdf 0), so pdf integrates over
// the upper hemisphere to 1 minus their probability: 0.02-2.8% on those files.
// Measured range: the files tabulate θi up to ~78-85° and pad the range to 90° with a copy of the
// last measured slice's rgb table, so beyond that slice's θi eval extrapolates (Mitsuba alike), and
// the factor D(m)/(4σ(wi))/cosθo lets such values reach 10^3-10^4 at grazing angles against at most a
// few hundred inside. measured_theta_max() is that θi (the instrument's limit; wo's side is measured
// over the hemisphere); eval still returns Mitsuba's values beyond it, but tabulate() and compare() do
// not use them.
// Like Mitsuba, nothing is clamped: real files hold slightly negative RGB values, and eval returns
// slightly negative f_r where they dominate. Where the result would not be finite (a zero sigma,
// an empty VNDF row, f overflowing at wo.z → 0, a NaN or infinite direction), eval returns 0.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/table.h"

namespace brdfz::rgl {

namespace detail {
class Marginal2D;     // the VNDF and luminance warps, private to the reader (formats/rgl/marginal2d.h)
struct KernelTables;  // what the batch kernels read (formats/rgl/kernels.h)
class Anisotropic;    // evaluation of files tabulated over φi too (formats/rgl/aniso.h)
}
struct SvdTensors;    // the compact stored form of the `rgl_svd` kind (rgl_svd.h)

// `slices` tables of rows × cols float32 samples, row-major (column index fastest), as stored.
struct Grids {
    std::size_t slices = 1, rows = 0, cols = 0;
    std::vector<float> values;
};

// The tensors of an RGB file that evaluation uses, in the file's layout (storage form; RglBrdf builds
// its warps from them). Every grid spans [0,1]² in the parameterisation's unit coordinates:
// x = u_θ = sqrt(θ / (π/2)), y = u_φ = (φ + π) / 2π. Below, for isotropic files (phi_i empty or one
// entry); with nφ >= 2 phi_i entries every "per θi" is "per (φi, θi)", φi outermost (formats/rgl/aniso.h).
struct Tensors {
    std::vector<float> phi_i;    // incident azimuths (radians) the tables are tabulated at; empty or one
                                 // entry (its value unused): isotropic
    std::vector<float> theta_i;  // incident elevations (radians) the θi-dependent grids are tabulated at
    Grids ndf;                   // 1 slice: microfacet distribution D(m), x = u_θm, y = u_φm (relative to φi;
                                 // absolute with more than two phi_i entries)
    Grids sigma;                 // 1 slice: projected microfacet area σ(wi), x = u_θi, y = u_φi
    Grids vndf;                  // one slice per θi: visible normal density, x = u_θm, y = u_φm
    Grids luminance;             // one slice per θi over the VNDF warp's unit square (as rgb), or
                                 // empty: then sampling uses the VNDF warp alone
    Grids rgb;                   // three slices per θi (R, G, B), over the VNDF warp's unit square
    bool jacobian = true;        // multiply by D(m) / (4·σ(wi)) (the file's `jacobian` flag)
};

class RglBrdf final : public Brdf {
public:
    // ValueError unless the shapes agree (grids at least 2×2, vndf with one slice and rgb with three
    // per θi, luminance empty or one slice per θi shaped like rgb's, theta_i and phi_i strictly
    // increasing) and theta_i, ndf, sigma, vndf and luminance are finite, vndf non-negative with every
    // slice integrating to a positive number. Non-finite rgb values are stored as 0. Negative luminance
    // values (noise in real files, which Mitsuba renders) are sampled as 0; when a θi slice of it has
    // no positive value, sampling uses the VNDF warp alone. check_renderable() holds the reader's
    // further rules.
    explicit RglBrdf(Tensors tensors);
    // The tensors expanded from `stored` (rgl_svd.h: make_svd_brdf), which nbytes() counts and the
    // container writes instead of the tensors.
    RglBrdf(Tensors tensors, std::shared_ptr<const SvdTensors> stored);
    ~RglBrdf() override;
    RglBrdf(const RglBrdf&) = delete;
    RglBrdf& operator=(const RglBrdf&) = delete;

    const Tensors& tensors() const { return tensors_; }
    // The compact form this material was expanded from; nullptr for a file's full tensors.
    const SvdTensors* svd() const { return svd_.get(); }

    int channels() const override { return 3; }
    // Bytes of the float32 tensors kept (theta_i, ndf, sigma, vndf, luminance, rgb), or of the compact
    // form it was expanded from; the derived warp tables are not counted.
    std::size_t nbytes() const override;
    std::string describe() const override;
    // The largest θi of a slice below 90° (a slice at 90°, to float precision, pads the range: nothing
    // is measured there); theta_i.back() when there is no such pad.
    double measured_theta_max() const override { return measured_theta_max_; }

protected:
    BRDFZ_BRDF_KERNELS;
    void pdf_batch(const Vec3* wo, const Vec3* wi, double* out, std::size_t n) const override;

private:
    detail::KernelTables kernel_tables() const;

    Tensors tensors_;
    std::unique_ptr<const detail::Marginal2D> vndf_;
    std::unique_ptr<const detail::Marginal2D> luminance_;  // null without a luminance tensor
    std::vector<float> rgb_;  // the rgb tensor in the kernels' layout (formats/rgl/kernels.h)
    std::unique_ptr<const detail::Anisotropic> aniso_;     // set for nφ >= 2, which then does all the work
    double measured_theta_max_;
    std::shared_ptr<const SvdTensors> svd_;
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
    // The same counts for every float field evaluation or sampling reads: ndf, sigma, vndf, luminance
    // (when present) and rgb, in that order.
    std::vector<std::pair<std::string, ValidityCounts>> fields;
};

// Counts of a field's values: valid (finite, >= 0), negative, NaN, Inf.
ValidityCounts count_values(const std::vector<float>& values);

// What Mitsuba 3's `measured` plugin cannot render (it loads anything: these give NaN, Inf or negative
// reflectance wherever they are read), refused with FormatError naming `path`, the field and its
// counts: rgb without a single finite value >= 0; ndf negative or not finite; sigma not positive (f
// divides by it) or not finite; vndf negative or not finite; luminance not finite. Negative rgb and
// luminance values are accepted (real files hold them; rgl.h above says how they are used). Both the
// .bsdf reader and the container's RGL module check this before building an RglBrdf.
void check_renderable(const std::string& path, const Tensors& tensors);

// Checks the whole field table (bounds, overflow, required fields and shapes) before reading any
// data. FormatError for an invalid file, UnsupportedError for a valid anisotropic or spectral one,
// IoError when the OS cannot read it; each names the file.
ReadResult read(const std::string& path);

}  // namespace brdfz::rgl
