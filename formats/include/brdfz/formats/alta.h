// ALTA text data files (`.dat`; ALTA library, Belcour, Pacanowski et al., documents/data-formats):
// scattered monochrome BRDF measurements, e.g. the CEA retro-reflective tapes (hal-01083366).
//
// Layout: header lines `#KEY value...` ('#' directly followed by a letter) before the first data
// line; other '#' lines and blank lines are comments; `#ALTA END HEADER` (or `#ALTA HEADER END`)
// may close the header. Keys read: `#DIM N P` (input and output dimensions), `#PARAM_IN NAME`,
// `#PARAM_OUT NAME` (absent: taken as INV_STERADIAN), `#VS v` (0, 1 or 2 extra confidence columns
// after the values, ALTA's interval of the first value; absent: 0), `#FORMAT` (only text files:
// `binary` is unsupported). Other keys (#SAMPLE, #URL, ...) are ignored.
// Then one sample per line: N input coordinates, the P values, and the #VS extra columns (read as
// numbers, not used).
//
// Outputs (#PARAM_OUT, with #DIM's P):
//   INV_STERADIAN                f_r in 1/sr; P = 1 (monochrome: channels = 1, the value repeated in
//                                R, G, B) or P = 3 (R, G, B: channels = 3)
//   INV_STERADIAN_COSINE_FACTOR  f_r·cosθ of the light (our θi: brdf.h's eval_cos), P = 1 or 3; read as
//                                f_r (divided by cosθi). ALTA's params.h calls it the cosine of the
//                                "output direction", the light in the renderer's naming ALTA shares
//                                with Mitsuba (whose eval includes the cosine towards the light).
//   RGB_COLOR                    f_r in 1/sr per channel, P = 3
// and these input parameterisations, with ALTA's light L as our wi and its view V as our wo:
//   CARTESIAN                  V.x, V.y, V.z, L.x, L.y, L.z (ALTA packs the view first), each vector
//                              normalised (any finite non-zero vector)
//   SPHERICAL_TL_PL_TV_PV      θl, φl, θv, φv: wi = (sinθl cosφl, sinθl sinφl, cosθl), wo likewise
//   ISOTROPIC_TL_TV_PROJ_DPHI  θl, x, y: wi = (sinθl, 0, cosθl); the view's polar angle is
//                              θv = ‖(x, y)‖ and its azimuth relative to the light atan2(y, x),
//                              wo = (sinθv·x/θv, sinθv·y/θv, cosθv), the +z normal when θv = 0.
//                              (ALTA's own inverse conversion measures Δφ the other way round;
//                              for isotropic data the two differ by a mirror image, y -> -y.)
//   RUSIN_TH_TD_PD             θh, θd, φd (φh = 0)
//   RUSIN_TH_TD                θh, θd with φd = π/2, where ALTA places these samples
//   RUSIN_TH_PH_TD_PD          θh, φh, θd, φd
// For the RUSIN family the difference vector d (polar angles θd, φd in the half-vector frame of
// coords.h, MERL's rotations) is ALTA's first vector, the view: wo = d rotated into place, and wi
// its mirror image about h. In coords.h's convention (d = wi) that is the sample (θh, φh, θd, φd + π);
// for a reciprocal BRDF the value is the same.
// Other parameterisations, output kinds or other P are valid ALTA files this reader does not handle:
// UnsupportedError.
//
// Checks: coordinates finite; θl, θv, θh, θd in [0, π]; Cartesian vectors non-zero. A sample on or below the horizon (wi or wo within
// 1e-9 rad of 90° or beyond; the CEA files hold rows at exactly θv = 90°) is dropped and counted in
// `below_horizon`; rows with NaN or infinite values are dropped and counted (in each class one of
// their values falls in); negative values are kept as measured and counted in `negative` (dropping only
// the noise below zero would bias the data).
#pragma once

#include <cstddef>
#include <string>

#include "brdfz/measurements.h"
#include "brdfz/table.h"

namespace brdfz::alta {

// Bounds checked before allocating.
inline constexpr std::size_t kMaxRows = std::size_t{1} << 24;
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 30;

struct ReadResult {
    MeasurementSet set;     // channels = 1, or 3 for three values per row
    std::string param_in;   // the file's input parameterisation, e.g. "ISOTROPIC_TL_TV_PROJ_DPHI"
    std::string param_out;  // its output: "INV_STERADIAN", "INV_STERADIAN_COSINE_FACTOR" or "RGB_COLOR"
    std::size_t rows = 0;   // data rows in the file, kept or not
    ValidityCounts counts;  // over rows, see above; `clamped` stays 0
};

// FormatError naming the file and line for a malformed file (missing or repeated #DIM / #PARAM_IN,
// #DIM not matching the parameterisation, rows of the wrong length, non-numbers, angles out of
// range, no usable row); UnsupportedError as above; IoError when the OS cannot read the file. The
// whole file is checked before samples are allocated.
ReadResult read(const std::string& path);

}  // namespace brdfz::alta
