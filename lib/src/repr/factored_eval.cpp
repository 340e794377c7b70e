// FactoredBrdf's batch eval kernel (factored.h), built for SSE2, for AVX2 + FMA and for AVX-512.
#include <algorithm>
#include <cstring>
#include <type_traits>

#include "detail/table_lookup.h"
#include "repr/factored_impl.h"

namespace brdfz {
namespace {

using detail::FactorView;

// ---------------------------------------------------------------------------------------------
// Evaluation: interpolation corners in factor rows and columns

// The blend's SIMD vectors (GCC vector extensions): 4 floats (SSE) or 8 (AVX). The kernel below is
// always inlined into its two entry points, so no vector crosses a call and the ABI note GCC warns
// about for 8-float vectors outside AVX code does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
typedef float Float4 __attribute__((vector_size(16)));
typedef float Float8 __attribute__((vector_size(32)));
template <int W>
struct FloatVector;
template <>
struct FloatVector<4> {
    using type = Float4;
};
template <>
struct FloatVector<8> {
    using type = Float8;
};
template <int W>
using FloatV = typename FloatVector<W>::type;

template <typename V>
[[gnu::always_inline]] inline V load(const float* p) {
    V v;
    std::memcpy(&v, p, sizeof v);  // unaligned: one movups
    return v;
}

constexpr std::size_t kBlock = 64;  // pairs per pass of the kernel

// The corners of a block's pairs: per corner, the factor rows to blend (row indices) and their
// weights. Stored by corner, not by pair, so the pass that computes them vectorises.
template <int NR, int NC>
struct BlockCorners {
    static constexpr int kRows = NR, kColumns = NC;
    int r[NR][kBlock], c[NC][kBlock];
    float rw[NR][kBlock], cw[NC][kBlock];
};
// h_dp: θh rows; (θd, φd) columns. hd_p: (θh, θd) rows; φd columns.
template <FactorLayout L>
using CornersOf = std::conditional_t<L == FactorLayout::HxDP, BlockCorners<2, 4>, BlockCorners<4, 2>>;

// Pair k's corners from its spans along θh, θd and φd. Branch-free.
template <FactorLayout L>
[[gnu::always_inline]] inline void set_corners(const GridSpec& g, const detail::Corners& s, std::size_t k,
                                               CornersOf<L>& out) {
    const auto hi = [](const detail::Span& a) { return static_cast<float>(a.t); };
    const auto lo = [](const detail::Span& a) { return static_cast<float>(1.0 - a.t); };
    // The 2-D axis: outer span a, inner span b, `inner` samples along b.
    const auto pairs = [&](const detail::Span& a, const detail::Span& b, int inner, int (&idx)[4][kBlock],
                           float (&w)[4][kBlock]) {
        idx[0][k] = a.i0 * inner + b.i0, idx[1][k] = a.i0 * inner + b.i1;
        idx[2][k] = a.i1 * inner + b.i0, idx[3][k] = a.i1 * inner + b.i1;
        w[0][k] = static_cast<float>((1.0 - a.t) * (1.0 - b.t)), w[1][k] = static_cast<float>((1.0 - a.t) * b.t);
        w[2][k] = static_cast<float>(a.t * (1.0 - b.t)), w[3][k] = static_cast<float>(a.t * b.t);
    };
    if constexpr (L == FactorLayout::HxDP) {
        out.r[0][k] = s.h.i0, out.r[1][k] = s.h.i1, out.rw[0][k] = lo(s.h), out.rw[1][k] = hi(s.h);
        pairs(s.d, s.p, g.n_phi_d, out.c, out.cw);
    } else {
        pairs(s.h, s.d, g.n_theta_d, out.r, out.rw);
        out.c[0][k] = s.p.i0, out.c[1][k] = s.p.i1, out.cw[0][k] = lo(s.p), out.cw[1][k] = hi(s.p);
    }
}

// The lane sums of three vectors, in lanes 0-2: pairwise adds of shuffled halves (a horizontal add
// per vector would take three times the shuffles).
[[gnu::always_inline]] inline Float4 lane_sums(const Float4 (&a)[3]) {
    const auto hadd = [](Float4 x, Float4 y) {
        return __builtin_shufflevector(x, y, 0, 2, 4, 6) + __builtin_shufflevector(x, y, 1, 3, 5, 7);
    };
    return hadd(hadd(a[0], a[1]), hadd(a[2], a[2]));
}
[[gnu::always_inline]] inline Float4 lane_sums(const Float8 (&a)[3]) {
    Float4 h[3];
    for (int i = 0; i < 3; ++i)
        h[i] = __builtin_shufflevector(a[i], a[i], 0, 1, 2, 3) + __builtin_shufflevector(a[i], a[i], 4, 5, 6, 7);
    return lane_sums(h);
}

// Pair k's transform-space values y_c = Σ_j mix_cj · (Σ_r rw_r U[r][j]) · (Σ_c cw_c V[c][j]), in
// float, W components at a time. Separate colour's mix is one-hot; multiplying by its zeros costs
// less than the gathers that would avoid it, and rank 3 and 4 (Grouped) skip it. The float sums are within ~1e-7 of the factors'
// magnitude, as the float32 factors themselves.
template <int W, bool Grouped, typename Corners>
[[gnu::always_inline]] inline void blend(const FactorView& f, const Corners& k, std::size_t i, float y[3]) {
    using V = FloatV<W>;
    constexpr int NR = Corners::kRows, NC = Corners::kColumns;
    const float* u[NR];
    const float* v[NC];
    for (int r = 0; r < NR; ++r) u[r] = f.u + static_cast<std::size_t>(k.r[r][i]) * f.width;
    for (int c = 0; c < NC; ++c) v[c] = f.v + static_cast<std::size_t>(k.c[c][i]) * f.width;
    const auto product = [&](std::size_t j) {
        V a = k.rw[0][i] * load<V>(u[0] + j), b = k.cw[0][i] * load<V>(v[0] + j);
        for (int r = 1; r < NR; ++r) a += k.rw[r][i] * load<V>(u[r] + j);
        for (int c = 1; c < NC; ++c) b += k.cw[c][i] * load<V>(v[c] + j);
        return a * b;
    };
    Float4 s;
    if constexpr (Grouped) {
        constexpr std::size_t kSteps = (12 + W - 1) / W;  // the 3 groups, in whole steps
        Float4 g[kSteps * W / 4];
        for (std::size_t step = 0; step < kSteps; ++step) {
            const V p = product(step * W);
            std::memcpy(&g[step * W / 4], &p, sizeof p);
        }
        const Float4 groups[3] = {g[0], g[1], g[2]};
        s = lane_sums(groups);
    } else {
        V acc[3] = {};
        for (std::size_t j = 0; j < f.width; j += W) {
            const V p = product(j);
            for (std::size_t ch = 0; ch < 3; ++ch) acc[ch] += load<V>(f.mix + ch * f.width + j) * p;
        }
        s = lane_sums(acc);
    }
    // At most the data's largest value: bins without data can reconstruct far beyond it (factor.h).
    for (int ch = 0; ch < 3; ++ch) y[ch] = std::min(s[ch], f.ceiling[ch]);
}

// Blocks of pairs in passes, as the tabular kernel: (1) the coordinates, branch-free so the compiler
// vectorises them (the rare pairs whose φd they flag as ill-conditioned recomputed exactly); (2) the
// corners, branch-free and vectorised too, and the prefetches of the factor rows when they miss the
// cache; (3) the blends; (4) the inverse transform, vectorised over the block. W: the blend's floats
// per step.
template <int W, FactorLayout L, bool Grouped>
[[gnu::always_inline]] inline void eval_pairs(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo,
                                              Rgb* out, std::size_t n, std::uint64_t& clamped) {
    const GridSpec& g = f.grid;
    const double off = g.sample_offset();
    detail::BinCoords coords[kBlock];
    CornersOf<L> corners;
    bool above[kBlock];
    float y[3 * kBlock];
    double values[3 * kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        const Vec3* a = wi + start;
        const Vec3* b = wo + start;
        for (std::size_t k = 0; k < m; ++k) coords[k] = detail::fast_bin_coords(g, a[k], b[k]);
        for (std::size_t k = 0; k < m; ++k) above[k] = (a[k].z > 0.0) & (b[k].z > 0.0);
        for (std::size_t k = 0; k < m; ++k)
            if (above[k] & !(coords[k].up <= g.n_phi_d)) [[unlikely]]  // kIllConditioned or NaN
                coords[k] = detail::bin_coords(g, a[k], b[k]);
        // One loop per kind of φd axis: a select per pair would compute both kinds of span.
        const auto set_all = [&](auto phi_d_span) {
            for (std::size_t k = 0; k < m; ++k) {
                const detail::BinCoords& c = coords[k];
                set_corners<L>(g,
                               {detail::clamped_span(c.uh - off, g.n_theta_h), detail::clamped_span(c.ud - off, g.n_theta_d),
                                phi_d_span(c.up - off, g.n_phi_d)},
                               k, corners);
            }
        };
        if (g.bilateral())
            set_all([](double c, int n) { return detail::clamped_span(c, n); });
        else
            set_all([](double c, int n) { return detail::periodic_span(c, n); });
        if (f.prefetch_u)
            for (std::size_t k = 0; k < m; ++k)
                for (const auto& r : corners.r) __builtin_prefetch(f.u + static_cast<std::size_t>(r[k]) * f.width);
        if (f.prefetch_v)
            for (std::size_t k = 0; k < m; ++k)
                for (const auto& c : corners.c) __builtin_prefetch(f.v + static_cast<std::size_t>(c[k]) * f.width);
        for (std::size_t k = 0; k < m; ++k) {
            if (above[k])
                blend<W, Grouped>(f, corners, k, y + 3 * k);
            else
                y[3 * k] = y[3 * k + 1] = y[3 * k + 2] = 0.0f;  // gives the value 0, not counted
        }
        detail::from_space_n(space, y, values, 3 * m, clamped);
        for (std::size_t k = 0; k < m; ++k) out[start + k] = {values[3 * k], values[3 * k + 1], values[3 * k + 2]};
    }
}

// The kernel's builds (runtime/kernels/simd.h: Builds). Single-pair eval runs the same one as the batch
// (bit for bit: FMA contraction makes the SSE2 build's results differ from the others' in the last bits).
// The AVX-512 one blends 8 floats per step as the AVX2 one (the factors' padding is the same), and runs
// the coordinates and the inverse transform 8 doubles wide.
template <FactorLayout L, bool Grouped>
struct EvalKernel {
    static constexpr bool kAvx512 = true, kFma = true;
    template <Simd S>
    static void run(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n,
                    std::uint64_t& clamped) {
        eval_pairs<S == Simd::Sse2 ? 4 : 8, L, Grouped>(f, space, wi, wo, out, n, clamped);
    }
};

template <bool Grouped>
void eval_kernel(detail::Simd simd, FactorLayout layout, const FactorView& f, FactorSpace space, const Vec3* wi,
                 const Vec3* wo, Rgb* out, std::size_t n, std::uint64_t& clamped) {
    using Signature = void(const FactorView&, FactorSpace, const Vec3*, const Vec3*, Rgb*, std::size_t, std::uint64_t&);
    using runtime::kernels::Builds;
    const auto kernel = layout == FactorLayout::HxDP ? Builds<EvalKernel<FactorLayout::HxDP, Grouped>, Signature>::at(simd)
                                                     : Builds<EvalKernel<FactorLayout::HDxP, Grouped>, Signature>::at(simd);
    kernel(f, space, wi, wo, out, n, clamped);
}

}  // namespace

void detail::eval_factors(Simd simd, FactorLayout layout, const FactorView& f, FactorSpace space, const Vec3* wi,
                          const Vec3* wo, Rgb* out, std::size_t n, std::uint64_t& clamped) {
    (f.grouped ? eval_kernel<true> : eval_kernel<false>)(simd, layout, f, space, wi, wo, out, n, clamped);
}

}  // namespace brdfz
