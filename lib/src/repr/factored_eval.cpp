// FactoredBrdf's batch eval kernel (factored.h), built for SSE2, for AVX2 + FMA and for AVX-512.
#include <algorithm>
#include <cstring>
#include <type_traits>

#include "brdfz/runtime/kernels/factored.h"
#include "detail/table_lookup.h"
#include "repr/factored_impl.h"

namespace brdfz {
namespace {

using detail::FactorView;

// ---------------------------------------------------------------------------------------------
// Evaluation: interpolation corners in factor rows and columns

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

// Pair k's corners from its spans along θh, θd and φd (runtime/kernels/factored.h). Branch-free.
template <FactorLayout L>
[[gnu::always_inline]] inline void set_corners(const GridSpec& g, const detail::Corners& s, std::size_t k,
                                               CornersOf<L>& out) {
    using namespace runtime::kernels;
    int rows[CornersOf<L>::kRows], cols[CornersOf<L>::kColumns];
    float rw[CornersOf<L>::kRows], cw[CornersOf<L>::kColumns];
    if constexpr (L == FactorLayout::HxDP) {
        factor_corners_1d(s.h, rows, rw);
        factor_corners_2d(s.d, s.p, g.n_phi_d, cols, cw);
    } else {
        factor_corners_2d(s.h, s.d, g.n_theta_d, rows, rw);
        factor_corners_1d(s.p, cols, cw);
    }
    for (int r = 0; r < CornersOf<L>::kRows; ++r) out.r[r][k] = rows[r], out.rw[r][k] = rw[r];
    for (int c = 0; c < CornersOf<L>::kColumns; ++c) out.c[c][k] = cols[c], out.cw[c][k] = cw[c];
}

// Pair i's transform-space values, W floats a step (runtime/kernels/factored.h: factor_sums, the
// runtime's own).
template <int W, bool Grouped, typename Corners>
[[gnu::always_inline]] inline void blend(const FactorView& f, const Corners& k, std::size_t i, float y[3]) {
    constexpr int NR = Corners::kRows, NC = Corners::kColumns;
    int rows[NR], cols[NC];
    float rw[NR], cw[NC];
    for (int r = 0; r < NR; ++r) rows[r] = k.r[r][i], rw[r] = k.rw[r][i];
    for (int c = 0; c < NC; ++c) cols[c] = k.c[c][i], cw[c] = k.cw[c][i];
    runtime::kernels::factor_sums<W, Grouped, NR, NC>(f, rows, rw, cols, cw, y);
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
        if (g.theta_h_warp == 0.0)
            for (std::size_t k = 0; k < m; ++k)
                coords[k] = detail::fast_bin_coords<runtime::kernels::ThetaHAxes::SquareRoot>(g, a[k], b[k]);
        else
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
