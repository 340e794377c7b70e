// The lookup kernel of every Rusinkiewicz table representation (TabularBrdf, CompactTableBrdf): direction
// pair -> bin coordinates -> nearest bin or interpolation corners -> values. Value storage is a policy,
// so float32, float16 and quantised tables share the coordinate arithmetic (and its exactness) and differ
// only in how a bin's three values are read. A Values policy provides
//   void load(std::size_t bin, float v[3]) const;   // the bin's values, NaN for an invalid channel
//   const void* address(std::size_t bin) const;    // where the bin's values lie, for prefetching
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <numbers>
#include <string>
#include <type_traits>

#include "brdfz/coords.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/table.h"
#include "detail/fast_math.h"
#include "detail/simd.h"

namespace brdfz::detail {

// ", symmetry none" or ", symmetry bilateral"; nothing on a reciprocal grid.
inline std::string symmetry_suffix(const GridSpec& g) {
    return g.reciprocal() ? "" : std::string(", symmetry ") + symmetry_name(g.symmetry);
}

// The start of a table's describe(): "tabular 90x90x180", or "bivariate 90x90" for one φd bin, and
// ", theta_d warp 0.6" on a warped θd axis, then symmetry_suffix.
inline std::string table_shape(const GridSpec& g) {
    std::string warp;
    if (g.theta_d_warp != 0.0) {
        char text[48];
        std::snprintf(text, sizeof text, ", theta_d warp %g", g.theta_d_warp);
        warp = text;
    }
    return (g.n_phi_d == 1 ? "bivariate " + std::to_string(g.n_theta_h) + "x" + std::to_string(g.n_theta_d)
                           : "tabular " + g.str()) +
           warp + symmetry_suffix(g);
}

// Continuous bin coordinates (θh, θd, φd) of a direction pair on a grid.
struct BinCoords {
    double uh, ud, up;
};

// MERL's arithmetic (see table.h): what nearest lookup must match bit for bit.
inline BinCoords bin_coords(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 h = half_vector(wi, wo);
    const Vec3 d = difference_vector(wi, half_frame(h));
    return {axis::theta_h_to_u(elevation(h), g.n_theta_h), g.theta_d_to_u(elevation(d)),
            g.phi_d_to_u(std::atan2(d.y, d.x))};
}

// bin_coords without asin, atan2 or a normalisation: every angle is an arctangent of two lengths
// in one (arbitrary) scale, from s = wi + wo, the unnormalised half vector:
//   θh = atan(|s_xy| / s_z),  θd = atan(|wi × s| / wi·s),
//   φd = atan(d_y / d_x) with d_x, d_y (half_frame's) both multiplied by |s|·|s_xy| > 0 (phi_d_coord).
// Within 5e-8 bins of bin_coords (angles to 2.2e-10 relative; rounding ~1e-16 / sinθd in φd), except
// where φd is ill-conditioned (θh or θd below 1e-6): there up is kIllConditioned, beyond any grid, for
// the callers to fall back to bin_coords. Branch-free, so the compiler vectorises it across pairs.
constexpr double kIllConditioned = 1e300;

// θd's bin coordinate on the grid's axis, from θd and cosθd: the warped axis (table.h) is a select,
// so the linear axis stays exact and the callers' loops stay branch-free.
[[gnu::always_inline]] inline double theta_d_coord(const GridSpec& g, double theta_d, double cos_d) {
    const double w = g.theta_d_warp;
    const double ud_linear = theta_d * (2.0 / std::numbers::pi) * g.n_theta_d;
    const double ud_warped = ((1.0 - w) * theta_d * (2.0 / std::numbers::pi) + w * (1.0 - cos_d)) * g.n_theta_d;
    return w == 0.0 ? ud_linear : ud_warped;
}

// φd's bin coordinate from (y, x), d_y and d_x in any one positive scale: fast_half_turn_angle folds
// the angle into [0, π] (a reciprocal grid's axis); the full circle (Symmetry::None) adds π where
// d_y < 0; the mirror fold (Symmetry::Bilateral) takes |d_y|, so |φd|. Selects, not branches, and on a
// reciprocal grid the arithmetic of the folded axis exactly.
[[gnu::always_inline]] inline double phi_d_coord(const GridSpec& g, double y, double x) {
    const bool full = g.full_circle();
    // |d_y| by masking its sign bit (all bits kept on the other axes): one AND per pair, not a select.
    const std::uint64_t keep = g.bilateral() ? ~(std::uint64_t{1} << 63) : ~std::uint64_t{0};
    const double folded = std::bit_cast<double>(std::bit_cast<std::uint64_t>(y) & keep);
    const double phi = fast_half_turn_angle(folded, x) + ((full & (y < 0.0)) ? std::numbers::pi : 0.0);
    return phi * (full ? 0.5 / std::numbers::pi : 1.0 / std::numbers::pi) * g.n_phi_d;
}

// Always inlined: a call per pair would keep the callers' coordinate loops from vectorising.
[[gnu::always_inline]] inline BinCoords fast_bin_coords(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 s = wi + wo;
    const double rxy2 = s.x * s.x + s.y * s.y;
    const double rxy = std::sqrt(rxy2);
    const double len = std::sqrt(rxy2 + s.z * s.z);
    const Vec3 cr{wi.y * s.z - wi.z * s.y, wi.z * s.x - wi.x * s.z, wi.x * s.y - wi.y * s.x};
    const double sin_d = std::sqrt(dot(cr, cr));  // sinθd·|s|
    const double theta_h = fast_half_turn_angle(rxy, s.z);
    const double theta_d = fast_half_turn_angle(sin_d, dot(wi, s));
    const double up = phi_d_coord(g, -cr.z * len, s.z * (wi.x * s.x + wi.y * s.y) - wi.z * rxy2);
    constexpr double kMinSin = 1e-6;
    const bool sure = (rxy > kMinSin * len) & (sin_d > kMinSin * len);
    return {std::sqrt(theta_h * (2.0 / std::numbers::pi)) * g.n_theta_h, theta_d_coord(g, theta_d, dot(wi, s) / len),
            std::max(up, sure ? 0.0 : kIllConditioned)};
}

// Clamp to [0, hi] with comparisons, NaN to 0: std::fmin/fmax are out-of-line libm calls here.
inline double clamp0(double u, double hi) { return u > 0.0 ? (u < hi ? u : hi) : 0.0; }
inline int bin_of(double u, int n) { return static_cast<int>(clamp0(u, n - 1.0)); }

// The bin of a fast_bin_coords coordinate, in `bin`; true when the coordinate is far enough from a bin
// edge (0 and n included) for that bin to be bin_coords' bin. False for NaN and kIllConditioned.
inline bool clear_bin(double u, int n, int& bin) {
    constexpr double kMargin = 1e-6;  // 20x fast_bin_coords' error bound (5e-8 bins)
    const double c = clamp0(u, n);
    bin = static_cast<int>(c);
    const double frac = c - bin;
    return static_cast<bool>((frac > kMargin) & (frac < 1.0 - kMargin) & (bin < n));  // &, not &&: no branch
}

// Out of line: rare, and it would crowd the hot loop.
[[gnu::noinline]] inline std::size_t exact_nearest_bin(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const BinCoords c = bin_coords(g, wi, wo);
    return g.index(bin_of(c.uh, g.n_theta_h), bin_of(c.ud, g.n_theta_d), bin_of(c.up, g.n_phi_d));
}

// The nearest bin given the pair's fast coordinates.
inline std::size_t nearest_bin(const GridSpec& g, const BinCoords& c, const Vec3& wi, const Vec3& wo) {
    int ih, id, ip;
    const bool ch = clear_bin(c.uh, g.n_theta_h, ih), cd = clear_bin(c.ud, g.n_theta_d, id),
               cp = clear_bin(c.up, g.n_phi_d, ip);
    return (ch & cd & cp) ? g.index(ih, id, ip) : exact_nearest_bin(g, wi, wo);
}

template <typename Values>
inline Rgb read_nearest(const Values& values, std::size_t bin) {
    float v[3];
    values.load(bin, v);
    Rgb f;
    for (int ch = 0; ch < 3; ++ch) f[ch] = std::isnan(v[ch]) ? 0.0 : v[ch];
    return f;
}

// Two neighbouring samples along a clamped axis and the weight of the second.
struct Span {
    int i0, i1;
    double t;
};

inline Span clamped_span(double c, int n) {
    c = clamp0(c, n - 1.0);
    const int i0 = static_cast<int>(c);
    const int i1 = i0 + 1 < n ? i0 + 1 : i0;
    return {i0, i1, c - i0};
}

// c is in [-0.5, n] (φd over the axis' range, minus the sample offset) or NaN: one wrap, not fmod.
inline Span periodic_span(double c, int n) {
    if (c < 0.0) c += n;
    if (!(c < n)) c = 0.0;  // c == n after rounding, or NaN
    const int i0 = static_cast<int>(c);
    return {i0, i0 + 1 < n ? i0 + 1 : 0, c - i0};
}

// φd's two samples: around the circle where the axis is periodic (reciprocal: φd ~ φd + π; none: the
// full circle); on the bilateral axis, whose ends 0 and π are mirror planes, clamped, which is the
// reflection there: a sample's mirror image about an end is the end sample itself (bin centres) or
// lies as far beyond the end as the sample inside it (bin starts), so the lookup is flat at the ends.
inline Span phi_d_span(const GridSpec& g, double c) {
    return g.bilateral() ? clamped_span(c, g.n_phi_d) : periodic_span(c, g.n_phi_d);
}

struct Corners {
    Span h, d, p;
};

// Linear lookup uses the fast coordinates (5e-8 bins off: ~1e-9 relative in the result) except where
// they flagged φd as ill-conditioned.
inline Corners linear_corners(const GridSpec& g, BinCoords c, const Vec3& wi, const Vec3& wo) {
    if (!(c.up <= g.n_phi_d)) [[unlikely]]  // kIllConditioned or NaN
        c = bin_coords(g, wi, wo);
    const double off = g.sample_offset();
    return {clamped_span(c.uh - off, g.n_theta_h), clamped_span(c.ud - off, g.n_theta_d),
            phi_d_span(g, c.up - off)};
}

// The blend runs across channels, as vectors of doubles (GCC vector extensions): the three channels
// and a spare lane in one AVX register (Wide, for kernels built for AVX2), or in two SSE2 registers.
// Within one function, so no such vector crosses a call (whose ABI depends on the instruction set).
// Each channel's arithmetic is the scalar one's (the same products, the same order of sums), so the
// result is the same to the bit in either form.
typedef double Doubles2 __attribute__((vector_size(16)));
typedef std::int64_t Mask2 __attribute__((vector_size(16)));
typedef double Doubles4 __attribute__((vector_size(32)));
typedef std::int64_t Mask4 __attribute__((vector_size(32)));
typedef float Floats4 __attribute__((vector_size(16)));

// A Values policy whose bins are three floats in memory, readable as four (Table pads its storage):
// read_linear then loads each corner as one vector instead of assembling it lane by lane.
template <typename Values>
concept FloatBins = requires(const Values& v) {
    { v.floats(std::size_t{}) } -> std::same_as<const float*>;
};

// A bin's values as kParts vectors (the last lane spare, its content unused).
template <bool Wide, typename Values, typename V>
[[gnu::always_inline]] inline void load_bin(const Values& values, std::size_t bin, V* x) {
    if constexpr (FloatBins<Values>) {
        Floats4 v;
        std::memcpy(&v, values.floats(bin), sizeof v);
        // Lane by lane, not __builtin_convertvector: GCC lowers that to two 128-bit conversions and a
        // spill even in the AVX2 build, where this is one vcvtps2pd.
        if constexpr (Wide)
            x[0] = Doubles4{v[0], v[1], v[2], v[3]};
        else
            x[0] = Doubles2{v[0], v[1]}, x[1] = Doubles2{v[2], v[3]};
    } else {
        float v[3];
        values.load(bin, v);
        if constexpr (Wide)
            x[0] = V{v[0], v[1], v[2], 0.0};
        else
            x[0] = V{v[0], v[1]}, x[1] = V{v[2], 0.0};
    }
}

template <bool Wide, typename Values>
[[gnu::always_inline]] inline Rgb read_linear(const GridSpec& g, const Values& values, const Corners& k) {
    using V = std::conditional_t<Wide, Doubles4, Doubles2>;
    using M = std::conditional_t<Wide, Mask4, Mask2>;
    constexpr int kParts = Wide ? 1 : 2;  // vectors per three channels
    constexpr int kLanes = Wide ? 4 : 2;
    const V zero = {};
    V sum[kParts], wsum[kParts];
    for (int i = 0; i < kParts; ++i) sum[i] = wsum[i] = zero;
    for (int a = 0; a < 2; ++a) {
        const int ih = a ? k.h.i1 : k.h.i0;
        const double wa = a ? k.h.t : 1.0 - k.h.t;
        for (int b = 0; b < 2; ++b) {
            const int id = b ? k.d.i1 : k.d.i0;
            const double wb = wa * (b ? k.d.t : 1.0 - k.d.t);
            const std::size_t row = g.index(ih, id, 0);  // the index is linear in φd's
            for (int p = 0; p < 2; ++p) {
                const double w = wb * (p ? k.p.t : 1.0 - k.p.t);
                V x[kParts];
                const V wv = w - zero;  // w in every lane: one broadcast (a lane loop became two shuffles)
                load_bin<Wide>(values, row + (p ? k.p.i1 : k.p.i0), x);
                for (int i = 0; i < kParts; ++i) {
                    // Invalid samples are NaN: they contribute neither value nor weight.
                    const M ok = x[i] == x[i];
                    sum[i] += ok ? wv * x[i] : zero;
                    wsum[i] += ok ? wv : zero;
                }
            }
        }
    }
    Rgb f;
    for (int i = 0; i < kParts; ++i) {
        const V q = wsum[i] > zero ? sum[i] / wsum[i] : zero;
        for (int j = 0; j < kLanes && i * kLanes + j < 3; ++j) f[i * kLanes + j] = q[j];
    }
    return f;
}

// Prefetches the lines of a linear lookup's corners: per (θh, θd) pair, both φd neighbours, which
// share a line unless they straddle a line boundary (for float32 bins, a third of the time).
template <typename Values>
[[gnu::always_inline]] inline void prefetch_corners(const GridSpec& g, const Values& values, int h0, int h1, int d0,
                                                    int d1, int p0, int p1) {
    for (int ih : {h0, h1})
        for (int id : {d0, d1}) {
            const std::size_t row = g.index(ih, id, 0);
            __builtin_prefetch(values.address(row + p0));
            __builtin_prefetch(values.address(row + p1));
        }
}

// f_r for one pair above the horizon.
template <bool Wide, typename Values>
[[gnu::always_inline]] inline Rgb eval_one(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi,
                                           const Vec3& wo) {
    const BinCoords c = fast_bin_coords(g, wi, wo);
    if (lookup == Lookup::Nearest) return read_nearest(values, nearest_bin(g, c, wi, wo));
    return read_linear<Wide>(g, values, linear_corners(g, c, wi, wo));
}

// Its two builds (detail/simd.h), as the batch kernels': the AVX2 one blends the corners in one register,
// without FMA, so both give the same bits.
template <typename Values>
[[gnu::flatten]] Rgb eval_one_sse2(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi,
                                   const Vec3& wo) {
    return eval_one<false>(g, values, lookup, wi, wo);
}
template <typename Values>
[[gnu::flatten, gnu::target("avx2")]] Rgb eval_one_avx2(const GridSpec& g, const Values& values, Lookup lookup,
                                                        const Vec3& wi, const Vec3& wo) {
    return eval_one<true>(g, values, lookup, wi, wo);
}

template <typename Values>
Rgb eval_table(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi, const Vec3& wo) {
    return (simd_level() >= Simd::Avx2Fma ? eval_one_avx2<Values> : eval_one_sse2<Values>)(g, values, lookup, wi, wo);
}

// Batch kernels (eval_table_batch, and sample_table_batch's weights) work in blocks of pairs, in passes
// over arrays of numbers, not of structs, so that the branch-free passes vectorise. As many pairs as
// the sampler draws at once (HalfVectorSampler::kBlock).
constexpr std::size_t kLookupBlock = 128;
// How far ahead of its read a linear lookup's eight lines are prefetched: far enough to hide a miss,
// near enough that the misses in flight stay within what the core can track. A whole block's
// prefetches at once would outrun it, and the first reads would wait behind the last prefetches.
constexpr std::size_t kLinearAhead = 16;

// A block's bin coordinates (BinCoords).
struct BlockCoords {
    double uh[kLookupBlock], ud[kLookupBlock], up[kLookupBlock];
    void set(std::size_t k, const BinCoords& c) { uh[k] = c.uh, ud[k] = c.ud, up[k] = c.up; }
};

// The table reads of a block of m pairs from their coordinates, in passes: (1) bins, or corners
// (branch-free, then linear_corners' fallback where φd was flagged); (2) the reads, each handed to
// emit(k, f), with the table lines of the pair kLinearAhead further on prefetched. In one pass a
// lookup's arithmetic is too long for the core to run ahead to the next pair's table read, so every
// cache miss stalled in turn. Pairs without use[k] are skipped; wi(k) and wo[k] are the pair, for the
// fallbacks. Each f is eval_table's, bit for bit.
template <bool Wide, typename Values, typename Wi, typename Emit>
[[gnu::always_inline]] inline void lookup_block(const GridSpec& g, const Values& values, Lookup lookup,
                                                const BlockCoords& c, const bool* use, std::size_t m, Wi wi,
                                                const Vec3* wo, Emit emit) {
    if (lookup == Lookup::Nearest) {
        std::size_t bins[kLookupBlock];
        for (std::size_t k = 0; k < m; ++k) {
            if (!use[k]) continue;
            bins[k] = nearest_bin(g, {c.uh[k], c.ud[k], c.up[k]}, wi(k), wo[k]);
            __builtin_prefetch(values.address(bins[k]));
        }
        for (std::size_t k = 0; k < m; ++k)
            if (use[k]) emit(k, read_nearest(values, bins[k]));
        return;
    }
    // Corners as arrays.
    int h0[kLookupBlock], h1[kLookupBlock], d0[kLookupBlock], d1[kLookupBlock], p0[kLookupBlock], p1[kLookupBlock];
    double ht[kLookupBlock], dt[kLookupBlock], pt[kLookupBlock];
    const double off = g.sample_offset();
    for (std::size_t k = 0; k < m; ++k) {
        const Span h = clamped_span(c.uh[k] - off, g.n_theta_h), d = clamped_span(c.ud[k] - off, g.n_theta_d),
                   p = periodic_span(c.up[k] - off, g.n_phi_d);
        h0[k] = h.i0, h1[k] = h.i1, ht[k] = h.t, d0[k] = d.i0, d1[k] = d.i1, dt[k] = d.t;
        p0[k] = p.i0, p1[k] = p.i1, pt[k] = p.t;
    }
    // The bilateral axis's φd spans in a pass of their own, so that the loop above stays the periodic
    // axes' own: a select per pair would compute both kinds of span.
    if (g.bilateral())
        for (std::size_t k = 0; k < m; ++k) {
            const Span p = clamped_span(c.up[k] - off, g.n_phi_d);
            p0[k] = p.i0, p1[k] = p.i1, pt[k] = p.t;
        }
    for (std::size_t k = 0; k < m; ++k)
        if (use[k] && !(c.up[k] <= g.n_phi_d)) [[unlikely]] {  // kIllConditioned or NaN
            const Corners x = linear_corners(g, {c.uh[k], c.ud[k], c.up[k]}, wi(k), wo[k]);
            h0[k] = x.h.i0, h1[k] = x.h.i1, ht[k] = x.h.t, d0[k] = x.d.i0, d1[k] = x.d.i1, dt[k] = x.d.t;
            p0[k] = x.p.i0, p1[k] = x.p.i1, pt[k] = x.p.t;
        }
    const auto prefetch = [&](std::size_t k) {
        if (use[k]) prefetch_corners(g, values, h0[k], h1[k], d0[k], d1[k], p0[k], p1[k]);
    };
    for (std::size_t k = 0; k < std::min(kLinearAhead, m); ++k) prefetch(k);
    for (std::size_t k = 0; k < m; ++k) {
        if (k + kLinearAhead < m) prefetch(k + kLinearAhead);
        if (use[k])
            emit(k, read_linear<Wide>(g, values, {{h0[k], h1[k], ht[k]}, {d0[k], d1[k], dt[k]}, {p0[k], p1[k], pt[k]}}));
    }
}

// Blocks of pairs: their coordinates (vectorised), then lookup_block.
template <bool Wide, typename Values>
[[gnu::always_inline]] inline void eval_table_passes(const GridSpec& g, const Values& values, Lookup lookup,
                                                     const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) {
    BlockCoords coords;
    bool above[kLookupBlock];
    for (std::size_t start = 0; start < n; start += kLookupBlock) {
        const std::size_t m = std::min(kLookupBlock, n - start);
        const Vec3* a = wi + start;
        const Vec3* b = wo + start;
        Rgb* o = out + start;
        for (std::size_t k = 0; k < m; ++k) coords.set(k, fast_bin_coords(g, a[k], b[k]));
        for (std::size_t k = 0; k < m; ++k) above[k] = (a[k].z > 0.0) & (b[k].z > 0.0);
        for (std::size_t k = 0; k < m; ++k)
            if (!above[k]) o[k] = Rgb{};
        lookup_block<Wide>(
            g, values, lookup, coords, above, m, [a](std::size_t k) -> const Vec3& { return a[k]; }, b,
            [o](std::size_t k, const Rgb& f) { o[k] = f; });
    }
}

// The kernel's two builds (detail/simd.h); the AVX2 one without FMA, so that both give eval_table's
// results to the bit.
template <typename Values>
[[gnu::flatten]] void eval_table_batch_sse2(const GridSpec& g, const Values& values, Lookup lookup, const Vec3* wi,
                                            const Vec3* wo, Rgb* out, std::size_t n) {
    eval_table_passes<false>(g, values, lookup, wi, wo, out, n);
}
template <typename Values>
[[gnu::flatten, gnu::target("avx2")]] void eval_table_batch_avx2(const GridSpec& g, const Values& values,
                                                                 Lookup lookup, const Vec3* wi, const Vec3* wo,
                                                                 Rgb* out, std::size_t n) {
    eval_table_passes<true>(g, values, lookup, wi, wo, out, n);
}

template <typename Values>
void eval_table_batch(const GridSpec& g, const Values& values, Lookup lookup, const Vec3* wi, const Vec3* wo,
                      Rgb* out, std::size_t n) {
    (simd_level() >= Simd::Avx2Fma ? eval_table_batch_avx2<Values> : eval_table_batch_sse2<Values>)(
        g, values, lookup, wi, wo, out, n);
}

}  // namespace brdfz::detail
