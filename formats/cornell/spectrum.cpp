// Spectral samples -> linear sRGB: CIE 1931 colour matching functions, the D65 illuminant and the
// sRGB primaries. See rgb_weights() in brdfz/formats/cornell.h for the definition.
//
// Data sources (tabulated here every 5 nm over 380..780 nm):
//  - CIE 1931 2° standard colorimetric observer x̄, ȳ, z̄: CIE 015:2018 "Colorimetry", 4th ed.,
//    table of the CIE 1931 standard observer (also CVRL, cvrl.org); cross-checked against the copy
//    of the CIE table in Mitsuba 3 (`cie1931_xyz`).
//  - CIE standard illuminant D65, relative spectral power (100 at 560 nm): ISO 11664-2 / CIE S 014-2.
//  - XYZ -> linear sRGB matrix: IEC 61966-2-1 (sRGB), derived from its primaries and D65 white.
#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/cornell.h"

namespace brdfz::cornell {
namespace {

struct CieRow {
    double nm, x, y, z, d65;
};

// clang-format off
constexpr CieRow kCie[] = {
    {380, 0.001368, 3.9e-05, 0.00645, 49.9755},
    {385, 0.002236, 6.4e-05, 0.01055, 52.3118},
    {390, 0.004243, 0.00012, 0.02005, 54.6482},
    {395, 0.00765, 0.000217, 0.03621, 68.7015},
    {400, 0.01431, 0.000396, 0.06785, 82.7549},
    {405, 0.02319, 0.00064, 0.1102, 87.1204},
    {410, 0.04351, 0.00121, 0.2074, 91.4860},
    {415, 0.07763, 0.00218, 0.3713, 92.4589},
    {420, 0.13438, 0.004, 0.6456, 93.4318},
    {425, 0.21477, 0.0073, 1.03905, 90.0570},
    {430, 0.2839, 0.0116, 1.3856, 86.6823},
    {435, 0.3285, 0.01684, 1.62296, 95.7736},
    {440, 0.34828, 0.023, 1.74706, 104.8650},
    {445, 0.34806, 0.0298, 1.7826, 110.9360},
    {450, 0.3362, 0.038, 1.77211, 117.0080},
    {455, 0.3187, 0.048, 1.7441, 117.4100},
    {460, 0.2908, 0.06, 1.6692, 117.8120},
    {465, 0.2511, 0.0739, 1.5281, 116.3360},
    {470, 0.19536, 0.09098, 1.28764, 114.8610},
    {475, 0.1421, 0.1126, 1.0419, 115.3920},
    {480, 0.09564, 0.13902, 0.81295, 115.9230},
    {485, 0.05795, 0.1693, 0.6162, 112.3670},
    {490, 0.03201, 0.20802, 0.46518, 108.8110},
    {495, 0.0147, 0.2586, 0.3533, 109.0820},
    {500, 0.0049, 0.323, 0.272, 109.3540},
    {505, 0.0024, 0.4073, 0.2123, 108.5780},
    {510, 0.0093, 0.503, 0.1582, 107.8020},
    {515, 0.0291, 0.6082, 0.1117, 106.2960},
    {520, 0.06327, 0.71, 0.07825, 104.7900},
    {525, 0.1096, 0.7932, 0.05725, 106.2390},
    {530, 0.1655, 0.862, 0.04216, 107.6890},
    {535, 0.22575, 0.91485, 0.02984, 106.0470},
    {540, 0.2904, 0.954, 0.0203, 104.4050},
    {545, 0.3597, 0.9803, 0.0134, 104.2250},
    {550, 0.43345, 0.99495, 0.00875, 104.0460},
    {555, 0.51205, 1, 0.00575, 102.0230},
    {560, 0.5945, 0.995, 0.0039, 100.0000},
    {565, 0.6784, 0.9786, 0.00275, 98.1671},
    {570, 0.7621, 0.952, 0.0021, 96.3342},
    {575, 0.8425, 0.9154, 0.0018, 96.0611},
    {580, 0.9163, 0.87, 0.00165, 95.7880},
    {585, 0.9786, 0.8163, 0.0014, 92.2368},
    {590, 1.0263, 0.757, 0.0011, 88.6856},
    {595, 1.0567, 0.6949, 0.001, 89.3459},
    {600, 1.0622, 0.631, 0.0008, 90.0062},
    {605, 1.0456, 0.5668, 0.0006, 89.8026},
    {610, 1.0026, 0.503, 0.00034, 89.5991},
    {615, 0.9384, 0.4412, 0.00024, 88.6489},
    {620, 0.85445, 0.381, 0.00019, 87.6987},
    {625, 0.7514, 0.321, 0.0001, 85.4936},
    {630, 0.6424, 0.265, 5e-05, 83.2886},
    {635, 0.5419, 0.217, 3e-05, 83.4939},
    {640, 0.4479, 0.175, 2e-05, 83.6992},
    {645, 0.3608, 0.1382, 1e-05, 81.8630},
    {650, 0.2835, 0.107, 0, 80.0268},
    {655, 0.2187, 0.0816, 0, 80.1207},
    {660, 0.1649, 0.061, 0, 80.2146},
    {665, 0.1212, 0.04458, 0, 81.2462},
    {670, 0.0874, 0.032, 0, 82.2778},
    {675, 0.0636, 0.0232, 0, 80.2810},
    {680, 0.04677, 0.017, 0, 78.2842},
    {685, 0.0329, 0.01192, 0, 74.0027},
    {690, 0.0227, 0.00821, 0, 69.7213},
    {695, 0.01584, 0.005723, 0, 70.6652},
    {700, 0.0113592, 0.004102, 0, 71.6091},
    {705, 0.00811092, 0.002929, 0, 72.9790},
    {710, 0.00579035, 0.002091, 0, 74.3490},
    {715, 0.00410946, 0.001484, 0, 67.9765},
    {720, 0.00289933, 0.001047, 0, 61.6040},
    {725, 0.00204919, 0.00074, 0, 65.7448},
    {730, 0.00143997, 0.00052, 0, 69.8856},
    {735, 0.000999949, 0.0003611, 0, 72.4863},
    {740, 0.000690079, 0.0002492, 0, 75.0870},
    {745, 0.000476021, 0.0001719, 0, 69.3398},
    {750, 0.000332301, 0.00012, 0, 63.5927},
    {755, 0.000234826, 8.48e-05, 0, 55.0054},
    {760, 0.00016615, 6e-05, 0, 46.4182},
    {765, 0.000117413, 4.24e-05, 0, 56.6118},
    {770, 8.30753e-05, 3e-05, 0, 66.8054},
    {775, 5.87065e-05, 2.12e-05, 0, 65.0941},
    {780, 4.15099e-05, 1.499e-05, 0, 63.3828},
};
// clang-format on
constexpr double kStep = 5.0;
constexpr std::size_t kRows = std::size(kCie);
static_assert(kRows == 81 && kCie[0].nm == kMinWavelength && kCie[kRows - 1].nm == kMaxWavelength);

constexpr double kXyzToSrgb[3][3] = {
    {3.2404542, -1.5371385, -0.4985314},
    {-0.9692660, 1.8760108, 0.0415560},
    {0.0556434, -0.2040259, 1.0572252},
};

// D65-weighted colour matching functions in sRGB: s(λ)·D65(λ)·M·(x̄, ȳ, z̄)(λ), linearly
// interpolated between the 5 nm rows.
Rgb srgb_density(double nm) {
    const double u = std::clamp((nm - kMinWavelength) / kStep, 0.0, static_cast<double>(kRows - 1));
    const std::size_t k = std::min(static_cast<std::size_t>(u), kRows - 2);
    const double t = u - static_cast<double>(k);
    const CieRow& a = kCie[k];
    const CieRow& b = kCie[k + 1];
    const double d65 = (1 - t) * a.d65 + t * b.d65;
    const double xyz[3] = {(1 - t) * a.x + t * b.x, (1 - t) * a.y + t * b.y, (1 - t) * a.z + t * b.z};
    Rgb rgb{};
    for (int c = 0; c < 3; ++c)
        rgb[c] = d65 * (kXyzToSrgb[c][0] * xyz[0] + kXyzToSrgb[c][1] * xyz[1] + kXyzToSrgb[c][2] * xyz[2]);
    return rgb;
}

// Unnormalised trapezoid weights of `wavelengths` for each channel.
std::vector<Rgb> trapezoid(std::span<const double> wavelengths) {
    const std::size_t n = wavelengths.size();
    std::vector<Rgb> w(n);
    for (std::size_t k = 0; k < n; ++k) {
        const double lo = wavelengths[k == 0 ? 0 : k - 1], hi = wavelengths[k + 1 == n ? k : k + 1];
        const Rgb d = srgb_density(wavelengths[k]);
        for (int c = 0; c < 3; ++c) w[k][c] = 0.5 * (hi - lo) * d[c];
    }
    return w;
}

}  // namespace

std::vector<Rgb> rgb_weights(std::span<const double> wavelengths) {
    if (wavelengths.size() < 2) throw ValueError("spectral to RGB: at least two wavelengths are needed");
    for (std::size_t k = 0; k < wavelengths.size(); ++k) {
        if (!(wavelengths[k] >= kMinWavelength && wavelengths[k] <= kMaxWavelength))
            throw ValueError("spectral to RGB: wavelength " + std::to_string(wavelengths[k]) + " nm outside the " +
                             "tabulated 380..780 nm");
        if (k > 0 && !(wavelengths[k] > wavelengths[k - 1]))
            throw ValueError("spectral to RGB: wavelengths must increase strictly");
    }
    // Each channel is normalised so that a flat spectrum of 1 gives exactly 1: the white point is D65
    // as the file samples it. The full 380..780 nm range sets the bar a sampling must reach: below 1%
    // of its white response a channel would be noise amplified, not colour.
    static const std::vector<Rgb> full = [] {
        std::vector<double> all(kRows);
        for (std::size_t k = 0; k < kRows; ++k) all[k] = kCie[k].nm;
        return trapezoid(all);
    }();
    constexpr const char* kChannelNames[] = {"red", "green", "blue"};
    std::vector<Rgb> w = trapezoid(wavelengths);
    for (int c = 0; c < 3; ++c) {
        double sum = 0, full_sum = 0;
        for (const Rgb& r : w) sum += r[c];
        for (const Rgb& r : full) full_sum += r[c];
        if (!(sum > 0.01 * full_sum))
            throw ValueError(std::string("spectral to RGB: the wavelengths cover too little of the visible range to ") +
                             "give a " + kChannelNames[c] + " response");
        for (Rgb& r : w) r[c] /= sum;
    }
    return w;
}

}  // namespace brdfz::cornell
