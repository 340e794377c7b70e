#include "brdfz/repr/compact_table.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/runtime/kernels/values.h"
#include "detail/table_lookup.h"
#include "repr/table_kernels.h"

namespace brdfz {
namespace {

static_assert(std::endian::native == std::endian::little, "float16 codes are kept little-endian, as stored");

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kMaxCode = 254;  // u8log codes 0..254 are values; 255 is invalid

inline std::uint16_t half_at(const std::uint8_t* codes, std::size_t i) {
    std::uint16_t h;
    std::memcpy(&h, codes + 2 * i, 2);
    return h;
}

// Lookup policies: the runtime's (brdfz/runtime/kernels/values.h).
using runtime::kernels::HalfValues;
using runtime::kernels::LogU8Values;

std::size_t code_size(TableDtype dtype) { return dtype == TableDtype::F16 ? 2 : 1; }

// Scales are powers of two in [2^-126, 2^112]: normal floats, so decoding's multiply is exact, and
// small enough that the largest half (65504) times the scale is a finite float.
constexpr int kMinHalfScaleExp = FLT_MIN_EXP - 1, kMaxHalfScaleExp = 112;  // FLT_MIN = 2^(FLT_MIN_EXP - 1)

// The power of two that puts `max` in [2^14, 2^15) (1 for an all-zero or empty channel).
double half_scale_for(float max) {
    if (!(max > 0.0f)) return 1.0;
    return std::ldexp(1.0, std::clamp(std::ilogb(max) - 14, kMinHalfScaleExp, kMaxHalfScaleExp));
}

// Per channel of a table: its valid values' range and weighted moments Σw, Σw·f, Σw·f², with the
// weights of the metrics (metrics.h): cos²θi where θi and θo are below 80°, 0 beyond. Grazing values
// can be orders of magnitude above the rest (RGL files extrapolate there) and would otherwise decide
// the gain for values that matter more.
struct ChannelStats {
    float min = std::numeric_limits<float>::infinity(), max = -std::numeric_limits<float>::infinity();
    double w = 0, wf = 0, wf2 = 0;
};

std::array<ChannelStats, 3> channel_stats(const Table& table) {
    const double kCos80 = std::cos(80.0 * std::numbers::pi / 180.0);
    const GridSpec& g = table.grid();
    std::array<ChannelStats, 3> s;
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const std::size_t bin = g.index(ih, id, ip);
                const auto [wi, wo] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                const double w = wi.z > kCos80 && wo.z > kCos80 ? wi.z * wi.z : 0.0;
                for (int ch = 0; ch < 3; ++ch) {
                    const float f = table.at(bin, ch);
                    if (std::isnan(f)) continue;
                    if (!(f >= 0.0f && f <= FLT_MAX))
                        throw ValueError("compact table: bin " + std::to_string(bin) + " holds " + std::to_string(f) +
                                         " (only finite values >= 0 can be quantised)");
                    s[ch].min = std::min(s[ch].min, f);
                    s[ch].max = std::max(s[ch].max, f);
                    s[ch].w += w;
                    s[ch].wf += w * f;
                    s[ch].wf2 += w * f * f;
                }
            }
    return s;
}

// Quantising ln(1 + g·f) in steps d, an error uniform in ±d/2 becomes ±d/2·(f + 1/g) in f; with
// d = L(g)/254, the expected weighted squared error is ∝ L(g)²·Σw(f + 1/g)². Minimised over gains
// spanning g·max = 1 (near-linear steps) to 1e10 (relative steps down to 1e-10 of the maximum).
// A channel with a single value has range 0: its codes are all 0, and scale 1/254 keeps the unused
// codes' decoded values finite.
ChannelCodec log_codec_for(const ChannelStats& s) {
    constexpr double kUnitRange = 1.0 / kMaxCode;
    if (!(s.max > 0.0f)) return {1.0, 0.0, kUnitRange};  // empty or all zero: code 0 decodes to 0
    double best = std::numeric_limits<double>::infinity(), best_gain = 1.0 / s.max;
    for (int j = 0; j <= 80; ++j) {
        const double g = std::pow(10.0, j / 8.0) / s.max;
        const double range = std::log1p(g * s.max) - std::log1p(g * s.min);
        const double cost = range * range * (s.wf2 + 2.0 * s.wf / g + s.w / (g * g));
        if (cost < best) best = cost, best_gain = g;
    }
    const double offset = std::log1p(best_gain * s.min);
    const double range = std::log1p(best_gain * s.max) - offset;
    return {best_gain, offset, range > 0.0 ? range / kMaxCode : kUnitRange};
}

}  // namespace

TableDtype parse_table_dtype(const std::string& name) {
    if (name == "f32") return TableDtype::F32;
    if (name == "f16") return TableDtype::F16;
    if (name == "u8log") return TableDtype::U8Log;
    throw ValueError("unknown table dtype '" + name + "' (expected f32, f16 or u8log)");
}

const char* table_dtype_name(TableDtype dtype) {
    switch (dtype) {
        case TableDtype::F32: return "f32";
        case TableDtype::F16: return "f16";
        case TableDtype::U8Log: return "u8log";
    }
    return "?";
}

std::uint16_t half_from_float(float f) {
    std::uint32_t x = std::bit_cast<std::uint32_t>(f);
    const auto sign = static_cast<std::uint16_t>((x >> 16) & 0x8000u);
    x &= 0x7fffffffu;
    if (x > 0x7f800000u) return sign | 0x7e00u;   // NaN
    if (x >= 0x477ff000u) return sign | 0x7c00u;  // Inf, or >= 65520, which rounds to it
    if (x < 0x38800000u)                          // below 2^-14: a subnormal half; exact scaling, then RNE
        return sign | static_cast<std::uint16_t>(std::nearbyint(std::bit_cast<float>(x) * 0x1p24f));
    x += 0xfffu + ((x >> 13) & 1u);  // round the 13 dropped bits to nearest, ties to even
    return sign | static_cast<std::uint16_t>((x - (112u << 23)) >> 13);
}

CompactTable CompactTable::encode(const Table& table, TableDtype dtype) {
    if (dtype == TableDtype::F32) throw ValueError("compact table: float32 tables are Table/TabularBrdf");
    const std::array<ChannelStats, 3> stats = channel_stats(table);
    std::array<ChannelCodec, 3> codecs;
    for (int ch = 0; ch < 3; ++ch)
        codecs[ch] = dtype == TableDtype::F16 ? ChannelCodec{1.0, 0.0, half_scale_for(stats[ch].max)}
                                              : log_codec_for(stats[ch]);
    const std::size_t n = 3 * table.bins();
    std::vector<std::uint8_t> codes(n * code_size(dtype));
    for (std::size_t i = 0; i < n; ++i) {
        const float f = table.data()[i];
        const ChannelCodec& c = codecs[i % 3];
        if (dtype == TableDtype::F16) {
            const std::uint16_t h = std::isnan(f) ? kInvalidF16 : half_from_float(static_cast<float>(f / c.scale));
            std::memcpy(codes.data() + 2 * i, &h, 2);
        } else {
            const double q = std::nearbyint((std::log1p(c.gain * f) - c.offset) / c.scale);
            codes[i] = std::isnan(f) ? kInvalidU8 : static_cast<std::uint8_t>(std::fmin(std::fmax(q, 0.0), kMaxCode));
        }
    }
    return CompactTable(table.grid(), dtype, std::move(codes), codecs);
}

CompactTable::CompactTable(GridSpec grid, TableDtype dtype, std::vector<std::uint8_t> codes,
                           std::array<ChannelCodec, 3> codecs)
    : grid_(grid), dtype_(dtype), codes_(std::move(codes)), codecs_(codecs) {
    grid_.validate();
    if (dtype_ == TableDtype::F32) throw ValueError("compact table: float32 tables are Table/TabularBrdf");
    if (codes_.size() != 3 * grid_.bins() * code_size(dtype_))
        throw ValueError("compact table: " + std::to_string(codes_.size()) + " bytes of codes for grid " + grid_.str() +
                         " (expected " + std::to_string(3 * grid_.bins() * code_size(dtype_)) + ")");
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelCodec& c = codecs_[ch];
        const std::string which = "compact table channel " + std::to_string(ch) + ": ";
        if (dtype_ == TableDtype::F16) {
            int e = 0;
            if (!(c.gain == 1.0 && c.offset == 0.0 && std::frexp(c.scale, &e) == 0.5 && e - 1 >= kMinHalfScaleExp &&
                  e - 1 <= kMaxHalfScaleExp))
                throw ValueError(which + "a float16 table's scale must be a power of two in [2^-126, 2^112]");
            half_scale_[ch] = static_cast<float>(c.scale);
        } else {
            if (!(std::isfinite(c.gain) && c.gain > 0.0 && std::isfinite(c.offset) && c.offset >= 0.0 &&
                  std::isfinite(c.scale) && c.scale > 0.0))
                throw ValueError(which + "u8log needs gain > 0, offset >= 0 and scale > 0, all finite");
            for (int q = 0; q <= kMaxCode; ++q)
                lut_[ch][q] = static_cast<float>(std::expm1(c.offset + c.scale * q) / c.gain);
            lut_[ch][kInvalidU8] = kNaN;
            if (!(lut_[ch][kMaxCode] <= FLT_MAX)) throw ValueError(which + "u8log codes decode beyond float range");
        }
    }
    if (dtype_ == TableDtype::F16)
        for (std::size_t i = 0; i < 3 * grid_.bins(); ++i) {
            const std::uint16_t h = half_at(codes_.data(), i);
            if ((h & 0x8000u) || ((h & 0x7c00u) == 0x7c00u && h != kInvalidF16))
                throw ValueError("compact table: float16 code " + std::to_string(h) + " at element " +
                                 std::to_string(i) + " is negative, infinite or a NaN other than the invalid code");
        }
}

float CompactTable::at(std::size_t bin, int channel) const {
    const std::size_t i = 3 * bin + channel;
    return dtype_ == TableDtype::F16 ? half_to_float(half_at(codes_.data(), i)) * half_scale_[channel]
                                     : lut_[channel][codes_[i]];
}

bool CompactTable::valid(std::size_t bin) const {
    return !std::isnan(at(bin, 0)) && !std::isnan(at(bin, 1)) && !std::isnan(at(bin, 2));
}

std::size_t CompactTable::valid_bins() const {
    std::size_t n = 0;
    for (std::size_t b = 0; b < bins(); ++b) n += valid(b);
    return n;
}

Table CompactTable::decode() const {
    Table t(grid_, Table::Uninitialized{});
    for (std::size_t b = 0; b < bins(); ++b)
        for (int ch = 0; ch < 3; ++ch) t.data()[3 * b + ch] = at(b, ch);
    return t;
}

CompactTableBrdf::CompactTableBrdf(CompactTable table, Lookup lookup, SamplerKind sampler)
    : LookupTableBrdf(lookup), table_(std::move(table)) {
    build_sampler(sampler);
}

CompactTableBrdf::CompactTableBrdf(CompactTable table, Lookup lookup, CompactSampler sampler)
    : LookupTableBrdf(lookup), table_(std::move(table)) {
    set_sampler(GridSampler(std::move(sampler)));
}

std::string CompactTableBrdf::describe() const {
    const GridSpec& g = table_.grid();
    return detail::table_shape(g) + (table_.dtype() == TableDtype::F16 ? " float16" : " uint8 log") + ", bin " +
           (g.position == BinPosition::Start ? "start" : "centre") + ", " + lookup_name(lookup()) + " lookup";
}

Rgb CompactTableBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    const GridSpec& g = table_.grid();
    if (table_.dtype() == TableDtype::F16)
        return detail::eval_table(g, HalfValues{table_.codes().data(), table_.half_scales()}, lookup(), wi, wo);
    return detail::eval_table(g, LogU8Values{table_.codes().data(), table_.lut()[0].data()}, lookup(), wi, wo);
}

void CompactTableBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    const GridSpec& g = table_.grid();
    if (table_.dtype() == TableDtype::F16)
        detail::eval_table_batch(g, HalfValues{table_.codes().data(), table_.half_scales()}, lookup(), wi, wo, out, n);
    else
        detail::eval_table_batch(g, LogU8Values{table_.codes().data(), table_.lut()[0].data()}, lookup(), wi, wo, out, n);
}

// As TabularBrdf: the fine sampler's weight comes with the draw, the compact one's from eval.
BrdfSample CompactTableBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    const HalfVectorSampler* fine = sampler().fine();
    if (!fine) return sample_compact(wo, u1, u2);
    const GridSpec& g = table_.grid();
    if (table_.dtype() == TableDtype::F16)
        return detail::sample_table(g, HalfValues{table_.codes().data(), table_.half_scales()}, lookup(), *fine, wo,
                                    u1, u2);
    return detail::sample_table(g, LogU8Values{table_.codes().data(), table_.lut()[0].data()}, lookup(), *fine, wo, u1, u2);
}

void CompactTableBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out,
                                    std::size_t n) const {
    const HalfVectorSampler* fine = sampler().fine();
    if (!fine) return Brdf::sample_batch(wo, u, out, n);
    const GridSpec& g = table_.grid();
    if (table_.dtype() == TableDtype::F16)
        detail::sample_table_batch(g, HalfValues{table_.codes().data(), table_.half_scales()}, lookup(), *fine, wo, u,
                                   out, n);
    else
        detail::sample_table_batch(g, LogU8Values{table_.codes().data(), table_.lut()[0].data()}, lookup(), *fine, wo, u, out,
                                   n);
}

}  // namespace brdfz
