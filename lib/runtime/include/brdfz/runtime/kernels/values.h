// How a table's bins are read (the Values policies of kernels/grid.h and of the core's batch kernels):
// load(bin, v) gives the bin's three channels as floats, NaN for an invalid channel; address(bin) is
// where they lie, for prefetching. One source for the library's tables and brdfz::runtime's.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "brdfz/runtime/kernels/math.h"

namespace brdfz::runtime::kernels {

// float32 values, read as they are.
struct Float32Values {
    const float* data;
    void load(std::size_t bin, float v[3]) const {
        const float* p = data + 3 * bin;
        v[0] = p[0], v[1] = p[1], v[2] = p[2];
    }
    const void* address(std::size_t bin) const { return data + 3 * bin; }
};

// binary16 codes (little-endian) times a power-of-two scale per channel; the code 0x7E00 is invalid.
// Codes are checked when a table is made (no sign, no infinity, no NaN but the invalid code), so a half
// decodes as its bits moved into a float's place times 2^112 (rebiasing the exponent), then the scale:
// two exact multiplies, where half_to_float's selects would dominate a linear lookup. Subnormal halves
// (values below 2^-28 of the channel's maximum) pass through float denormals, so they read as 0 where
// the caller runs with denormals-are-zero.
struct HalfValues {
    static constexpr std::uint16_t kInvalid = 0x7E00;
    const std::uint8_t* codes;
    std::array<float, 3> scale;
    void load(std::size_t bin, float v[3]) const {
        for (int ch = 0; ch < 3; ++ch) {
            std::uint16_t h;
            std::memcpy(&h, codes + 2 * (3 * bin + ch), 2);
            const float f = bits_as<float>(static_cast<std::uint32_t>(h) << 13) * 0x1p112f * scale[ch];
            v[ch] = h == kInvalid ? std::numeric_limits<float>::quiet_NaN() : f;
        }
    }
    const void* address(std::size_t bin) const { return codes + 6 * bin; }
};

// 8-bit codes decoded by a table of 256 floats per channel (NaN for the invalid code 255).
struct LogU8Values {
    const std::uint8_t* codes;
    const float* lut;  // 3 × 256
    void load(std::size_t bin, float v[3]) const {
        const std::uint8_t* c = codes + 3 * bin;
        for (int ch = 0; ch < 3; ++ch) v[ch] = lut[256 * ch + c[ch]];
    }
    const void* address(std::size_t bin) const { return codes + 3 * bin; }
};

}  // namespace brdfz::runtime::kernels
