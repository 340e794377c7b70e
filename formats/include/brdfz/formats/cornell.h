// Cornell gonioreflectometer spectral BRDFs (Program of Computer Graphics, Cornell University; the
// car paints shipped with pbrt-v2's scenes): text `.brdf` files of scattered measurements.
//
// Layout: '#' comment lines and blank lines anywhere; the number of wavelengths n (an integer alone
// on its line); the n wavelengths in nm (strictly increasing, over one or more lines); then one
// record per line: θi φi θo φo (radians) followed by n spectral values of f_r (1/sr).
//
// Angles: θ is the polar angle from the normal, φ the azimuth from +x, and both directions point
// away from the surface: wi = (sinθi cosφi, sinθi sinφi, cosθi), wo likewise (brdf.h). Checked
// against the data: in the three shipped car paints every θi slice peaks in the plane of incidence
// on the forward side, φo = φi + π, and for the high-gloss cayman and mystique at θo ≈ θi (the
// mirror direction, within the measurement spacing; e.g. θi = 80°, θo = 79°); garnet red, a
// medium-gloss paint, peaks off-specular towards grazing for θi >= 50°.
//
// Colour: each spectrum becomes linear sRGB as the reflected colour under CIE illuminant D65 (the
// sRGB white), integrated with the file's own wavelengths: rgb_c = Σ_k w_c(λ_k)·f(λ_k), see
// rgb_weights(). D65 rather than the equal-energy illuminant E because D65 is sRGB's own white:
// no chromatic adaptation is needed, and a spectrally flat BRDF of level s gives RGB (s, s, s)
// exactly (the white is normalised per channel over the file's sampling).
//
// Validity, per record: a record on or below the horizon (θi or θo within 1e-9 rad of π/2 or
// beyond) is dropped and counted in `below_horizon`; a record with a NaN or infinite spectral value
// is dropped and counted in `nan` / `inf`. Negative values are kept as measured (dropping only the
// noise below zero would bias the data upward) and counted: `negative` counts kept records whose RGB
// has a negative channel (a negative spectral value, or a saturated colour outside the sRGB gamut),
// `negative_spectral` those with a negative spectral value. `valid` counts the other kept records.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "brdfz/measurements.h"
#include "brdfz/table.h"

namespace brdfz::cornell {

// Wavelength range of the tabulated colour matching functions (nm).
inline constexpr double kMinWavelength = 380.0, kMaxWavelength = 780.0;
// Bounds checked before allocating.
inline constexpr std::size_t kMaxWavelengths = 1024;
inline constexpr std::size_t kMaxRecords = std::size_t{1} << 22;
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 30;

struct ReadResult {
    MeasurementSet set;               // channels = 3: linear sRGB f_r in 1/sr
    std::vector<double> wavelengths;  // nm, as in the file
    std::size_t records = 0;          // records in the file, kept or not
    ValidityCounts counts;            // over records, see above; `clamped` stays 0
    std::size_t negative_spectral = 0;
};

// FormatError naming the file and line for a malformed file (bad count, non-numbers, records of the
// wrong length, angles that are not finite or polar angles outside [0, π], wavelengths not strictly
// increasing, no record at all, no usable record); UnsupportedError for wavelengths outside
// 380..780 nm or too narrow a range for every channel to respond; IoError when the OS cannot read
// the file. The whole file is checked before samples are allocated.
ReadResult read(const std::string& path);

// Weights w[k] with rgb_c = Σ_k w[k][c]·s(λ_k) for a spectrum s sampled at `wavelengths` (nm): the
// trapezoid rule over the samples of D65(λ)·M·(x̄, ȳ, z̄)(λ), M the XYZ -> linear sRGB matrix,
// normalised so that Σ_k w[k][c] = 1 (a flat spectrum of 1 gives (1, 1, 1)). ValueError unless
// there are at least two wavelengths, strictly increasing, inside [kMinWavelength, kMaxWavelength],
// spanning enough of the visible range for every channel to respond.
std::vector<Rgb> rgb_weights(std::span<const double> wavelengths);

}  // namespace brdfz::cornell
