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
#include "brdfz/runtime/kernels/grid.h"
#include "detail/fast_math.h"

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
    if (g.theta_h_warp != 0.0) {
        char text[48];
        std::snprintf(text, sizeof text, ", theta_h warp %.3g deg", g.theta_h_warp * 180.0 / std::numbers::pi);
        warp += text;
    }
    return (g.n_phi_d == 1 ? "bivariate " + std::to_string(g.n_theta_h) + "x" + std::to_string(g.n_theta_d)
                           : "tabular " + g.str()) +
           warp + symmetry_suffix(g);
}

// The scalar lookup arithmetic is the runtime's (brdfz/runtime/kernels/grid.h), the one source the
// library and brdfz::runtime share; the batch kernels below run it across pairs.
using runtime::kernels::BinCoords;
using runtime::kernels::bin_coords;
using runtime::kernels::bin_of;
using runtime::kernels::clamp0;
using runtime::kernels::clamped_span;
using runtime::kernels::clear_bin;
using runtime::kernels::Corners;
using runtime::kernels::fast_bin_coords;
using runtime::kernels::kIllConditioned;
using runtime::kernels::linear_corners;
using runtime::kernels::nearest_bin;
using runtime::kernels::periodic_span;
using runtime::kernels::phi_d_coord;
using runtime::kernels::phi_d_span;
using runtime::kernels::Span;
using runtime::kernels::theta_d_coord;
using runtime::kernels::theta_h_coord;

template <typename Values>
inline Rgb read_nearest(const Values& values, std::size_t bin) {
    Rgb f;
    runtime::kernels::read_nearest(values, bin, f.data());
    return f;
}

// The linear blend across channels, as an Rgb. Blend: a target's BlendLanes (lib/runtime/src/
// blend_lanes-inl.h, the runtime's too), whose blend gives grid.h's blend_linear's bits.
template <typename Blend, typename Values>
[[gnu::always_inline]] inline Rgb read_linear(const GridSpec& g, const Values& values, const Corners& k) {
    Rgb f;
    Blend::blend(g, values, k, f.data());
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
template <typename Blend, typename Values>
[[gnu::always_inline]] inline Rgb eval_one(const GridSpec& g, const Values& values, Lookup lookup, const Vec3& wi,
                                           const Vec3& wo) {
    const BinCoords c = fast_bin_coords(g, wi, wo);
    if (lookup == Lookup::Nearest) return read_nearest(values, nearest_bin(g, c, wi, wo));
    return read_linear<Blend>(g, values, linear_corners(g, c, wi, wo));
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
template <typename Blend, typename Values, typename Wi, typename Emit>
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
            emit(k, read_linear<Blend>(g, values, {{h0[k], h1[k], ht[k]}, {d0[k], d1[k], dt[k]}, {p0[k], p1[k], pt[k]}}));
    }
}

// Blocks of pairs: their coordinates (vectorised), then lookup_block.
template <typename Blend, typename Values>
[[gnu::always_inline]] inline void eval_table_passes(const GridSpec& g, const Values& values, Lookup lookup,
                                                     const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) {
    BlockCoords coords;
    bool above[kLookupBlock];
    for (std::size_t start = 0; start < n; start += kLookupBlock) {
        const std::size_t m = std::min(kLookupBlock, n - start);
        const Vec3* a = wi + start;
        const Vec3* b = wo + start;
        Rgb* o = out + start;
        if (g.theta_h_warp == 0.0)
            for (std::size_t k = 0; k < m; ++k)
                coords.set(k, fast_bin_coords<runtime::kernels::ThetaHAxes::SquareRoot>(g, a[k], b[k]));
        else
            for (std::size_t k = 0; k < m; ++k) coords.set(k, fast_bin_coords(g, a[k], b[k]));
        for (std::size_t k = 0; k < m; ++k) above[k] = (a[k].z > 0.0) & (b[k].z > 0.0);
        for (std::size_t k = 0; k < m; ++k)
            if (!above[k]) o[k] = Rgb{};
        lookup_block<Blend>(
            g, values, lookup, coords, above, m, [a](std::size_t k) -> const Vec3& { return a[k]; }, b,
            [o](std::size_t k, const Rgb& f) { o[k] = f; });
    }
}

}  // namespace brdfz::detail
