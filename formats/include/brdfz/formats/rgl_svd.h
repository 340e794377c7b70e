// An isotropic RGL-EPFL material kept in its own parameterisation, compactly (the `rgl_svd` kind,
// docs/repr-specs.md): the file's grids are adapted to the material (its VNDF warp puts the RGB samples
// where the measured microfacet distribution has its mass), so a sharp specular peak that a
// Rusinkiewicz grid must resolve is already spread over the whole table. What is stored:
//   - ndf and sigma as float16 scaled by a power of two (the largest value at most 2^15), one row of
//     each when their rows are the same;
//   - the rgb tensor's θi slices up to the first at or beyond 80° (the rest pad the range with copies
//     of it) as a rank-K product in float16, or in int8 with a step per block of 32 codes (about half
//     the bytes; the second factor refitted to the first's rounded values): rows (slice, column x),
//     columns (channel, grid row y), so
//     the channels share the slices' factors; the factorisation weighs each row by the solid angle and
//     cosines its slice covers over θi < 80° and by the microfacet distribution at the column's θm
//     (power `weight`), so the error falls where the metrics over directions and a renderer look;
//   - theta_i and the jacobian flag.
//   - each channel's smallest value in the file's rgb, which the product is clamped to (the files hold
//     negative values, reproduced as Mitsuba does; a low-rank product undershoots below the rest);
// What is derived when it is read: vndf from ndf (D(m)·max(0, wi·m) in the unit square's measure, as the
// RGL-EPFL files' own are: the rgb samples lie where that warp puts them, so a file whose vndf is
// otherwise, such as brdfz's RGL writer's, is refused) and the luminance tensor from rgb (Rec. 709 Y, as
// the files compute it), so it samples as the file does.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "brdfz/formats/rgl.h"

namespace brdfz::rgl {

// How the factors are stored.
enum class SvdDtype { F16, I8 };

struct SvdTensors {
    using Dtype = SvdDtype;
    std::vector<float> theta_i;      // the file's, every slice
    bool jacobian = true;
    std::size_t ndf_rows = 0, ndf_cols = 0, sigma_rows = 0, sigma_cols = 0;
    // float16 bits of value · 2^-exponent, rows × cols, or one row when every row is the same (an
    // isotropic material's)
    std::vector<std::uint16_t> ndf, sigma;
    int ndf_exponent = 0, sigma_exponent = 0;
    std::size_t vndf_rows = 0, vndf_cols = 0;
    std::size_t slices = 0;          // θi slices factored; slices beyond repeat the last of them
    std::size_t rows = 0, cols = 0;  // the rgb grid
    std::size_t rank = 0;
    // The factors, (slice, column) × rank and (channel, grid row) × rank, row-major: float16 bits in u
    // and v, or int8 codes in u8 and v8 times a step per block and factor: u's per slice (u_scale,
    // slices × rank), v's per channel (v_scale, 3 × rank), float16 bits of step·2^-exponent.
    Dtype dtype = Dtype::F16;
    std::vector<std::uint16_t> u, v;
    std::vector<std::int8_t> u8, v8;
    std::vector<std::uint16_t> u_scale, v_scale;
    int u_scale_exponent = 0, v_scale_exponent = 0;
    bool luminance = true;           // derive a luminance tensor for sampling
    // Per channel, the least value the expanded rgb takes (-infinity: no floor, as files of container
    // version 8 are read).
    std::array<float, 3> floor{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                               -std::numeric_limits<float>::infinity()};

    bool has_floor() const { return std::isfinite(floor[0]) || std::isfinite(floor[1]) || std::isfinite(floor[2]); }

    // The stored bytes: every float16 and int8 value, theta_i as float32.
    std::size_t nbytes() const;
};

inline constexpr std::size_t kMaxSvdRank = 96;

// The vndf tensor an isotropic file's ndf implies, on the file's vndf grid (slices, rows, cols).
Grids derived_vndf(const std::vector<float>& theta_i, const Grids& ndf, std::size_t rows, std::size_t cols);

// Whether the file's vndf is, as a measurement's, the one its ndf implies: each slice as a density within
// half its mean density of it (the shared RGL-EPFL files within 0.2, most within 1e-4; the warp brdfz's
// writer chooses for its samples several times off). The metrics judge what the difference costs.
bool vndf_is_derived(const Tensors& tensors);

// ValueError for an anisotropic material, one whose vndf is not derived from its ndf, a rank outside [1, min(kMaxSvdRank, the factored matrix's
// columns)] or a weight power outside [0, 4].
SvdTensors factor(const Tensors& tensors, std::size_t rank, double weight_power, SvdDtype dtype = SvdDtype::F16);

// The tensors an RglBrdf evaluates; ValueError for shapes that disagree (as read from a file, checked
// before allocating).
Tensors expand(const SvdTensors& stored);

// An RglBrdf of expand(stored) that reports the stored bytes and keeps `stored` for the container.
std::unique_ptr<RglBrdf> make_svd_brdf(SvdTensors stored);

}  // namespace brdfz::rgl
