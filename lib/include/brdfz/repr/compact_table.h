// Compact Rusinkiewicz tables: a Table's values kept as float16 or 8-bit log-quantised codes, in memory
// as well as on disk (renderer memory is the point), and decoded in the lookup. The lookup itself
// (nearest bit-identical to MERL's, linear skipping invalid samples) is TabularBrdf's, shared.
//
// Element types, each with per-channel parameters (ChannelCodec):
//   f16    IEEE half codes h times a power-of-two `scale` per channel, chosen so the channel's largest
//          value lands in [2^14, 2^15): no overflow, 2^-11 relative precision down to 2^-28 of the
//          largest value, and a value that is a half times the scale is stored exactly.
//          Invalid channel: code 0x7E00 (a quiet NaN).
//   u8log  code q = round((ln(1 + gain·f) − offset) / scale) in 0..254, decoded f = (exp(offset + scale·q) − 1) / gain:
//          a relative step of about `scale` for f ≫ 1/gain, an absolute one of about scale/gain below.
//          offset and scale span the channel's valid values; gain minimises the expected quantisation
//          error of f·cosθi (the metrics' weighting). Code 255 marks an invalid channel.
// A grid with one φd bin is a bivariate (θh, θd) table (Romeiro et al. 2008): eval ignores φd.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/table.h"

namespace brdfz {

enum class TableDtype { F32, F16, U8Log };

TableDtype parse_table_dtype(const std::string& name);  // "f32" | "f16" | "u8log"; ValueError otherwise
const char* table_dtype_name(TableDtype dtype);         // "f32", "f16", "u8log"

// IEEE binary16 <-> binary32. half_to_float (the runtime's, brdfz/runtime/kernels/math.h) is exact for
// every code, also under flush-to-zero modes; half_from_float rounds to nearest even.
using runtime::kernels::half_to_float;
std::uint16_t half_from_float(float f);

// How one channel's codes decode (see the header comment). f16 uses `scale` only.
struct ChannelCodec {
    double gain = 1.0, offset = 0.0, scale = 1.0;
    bool operator==(const ChannelCodec&) const = default;
};

class CompactTable {
public:
    static constexpr std::uint16_t kInvalidF16 = 0x7E00;
    static constexpr std::uint8_t kInvalidU8 = 255;

    // Quantises a float32 table; its invalid channels stay invalid. ValueError for dtype F32 (that is
    // TabularBrdf's Table) or a value that does not fit (negative, or above 65504·2^112 ≈ 3.4e38).
    static CompactTable encode(const Table& table, TableDtype dtype);

    // From stored codes: `codes` holds bins·3 elements (little-endian halves for F16) in Table's order.
    // ValueError naming the problem for a wrong size, bad parameters, or a code that is neither a
    // finite non-negative value nor the invalid code.
    CompactTable(GridSpec grid, TableDtype dtype, std::vector<std::uint8_t> codes, std::array<ChannelCodec, 3> codecs);

    const GridSpec& grid() const { return grid_; }
    std::size_t bins() const { return grid_.bins(); }
    TableDtype dtype() const { return dtype_; }
    const std::vector<std::uint8_t>& codes() const { return codes_; }
    const std::array<ChannelCodec, 3>& codecs() const { return codecs_; }

    // What the representation stores: the codes plus the three codecs (float64 each, as written).
    std::size_t nbytes() const { return codes_.size() + 3 * 3 * sizeof(double); }

    // A channel's decoded value; NaN when invalid.
    float at(std::size_t bin, int channel) const;
    bool valid(std::size_t bin) const;
    std::size_t valid_bins() const;
    // The decoded float32 table (what lookups read).
    Table decode() const;

    // Decoding state for the lookup kernel: halves' scales, and u8log's table of the 256 codes per channel.
    const std::array<float, 3>& half_scales() const { return half_scale_; }
    const std::array<std::array<float, 256>, 3>& lut() const { return lut_; }

    bool operator==(const CompactTable& other) const {
        return grid_ == other.grid_ && dtype_ == other.dtype_ && codes_ == other.codes_ && codecs_ == other.codecs_;
    }

private:
    GridSpec grid_;
    TableDtype dtype_;
    std::vector<std::uint8_t> codes_;
    std::array<ChannelCodec, 3> codecs_;
    std::array<float, 3> half_scale_{};
    std::array<std::array<float, 256>, 3> lut_{};
};

class CompactTableBrdf final : public LookupTableBrdf {
public:
    explicit CompactTableBrdf(CompactTable table, Lookup lookup = Lookup::Linear,
                              SamplerKind sampler = SamplerKind::Compact);
    CompactTableBrdf(CompactTable table, Lookup lookup, CompactSampler sampler);

    const CompactTable& table() const { return table_; }
    std::size_t nbytes() const override { return table_.nbytes(); }
    std::string describe() const override;
    const GridSpec* grid() const override { return &table_.grid(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override;
    void sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const override;

private:
    CompactTable table_;
};

}  // namespace brdfz
