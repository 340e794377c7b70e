// FactoredBrdf's batch eval kernel (factored.h), compiled for each Highway target (foreach_target.h
// includes this file again for each; lib/runtime/src/hwy_dispatch.h picks one at run time). Its sums are
// the target's FactorLanes (lib/runtime/src/factor_lanes-inl.h), brdfz::runtime's too.
#ifndef BRDFZ_REPR_FACTORED_EVAL_ONCE
#define BRDFZ_REPR_FACTORED_EVAL_ONCE
#include <algorithm>
#include <cstring>
#include <type_traits>

#include "brdfz/runtime/kernels/factored.h"
#include "hwy_dispatch.h"
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

// Pair i's transform-space values (Sums: runtime/kernels/factored.h's sums policy).
template <typename Sums, bool Grouped, typename Corners>
[[gnu::always_inline]] inline void blend(const FactorView& f, const Corners& k, std::size_t i, float y[3]) {
    constexpr int NR = Corners::kRows, NC = Corners::kColumns;
    int rows[NR], cols[NC];
    float rw[NR], cw[NC];
    for (int r = 0; r < NR; ++r) rows[r] = k.r[r][i], rw[r] = k.rw[r][i];
    for (int c = 0; c < NC; ++c) cols[c] = k.c[c][i], cw[c] = k.cw[c][i];
    Sums::template sums<Grouped, NR, NC>(f, rows, rw, cols, cw, y);
}

// Blocks of pairs in passes, as the tabular kernel: (1) the coordinates, branch-free so the compiler
// vectorises them (the rare pairs whose φd they flag as ill-conditioned recomputed exactly); (2) the
// corners, branch-free and vectorised too, and the prefetches of the factor rows when they miss the
// cache; (3) the blends; (4) the inverse transform, vectorised over the block.
template <typename Sums, FactorLayout L, bool Grouped>
[[gnu::always_inline]] inline void eval_pairs(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo,
                                              Rgb* out, std::size_t n, std::uint64_t& clamped) {
    using runtime::kernels::ThetaHAxes;
    constexpr bool kFused = Sums::kFused;  // the coordinates and the inverse transform fuse as the sums
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
                coords[k] = detail::fast_bin_coords<ThetaHAxes::SquareRoot, kFused>(g, a[k], b[k]);
        else
            for (std::size_t k = 0; k < m; ++k) coords[k] = detail::fast_bin_coords<ThetaHAxes::Any, kFused>(g, a[k], b[k]);
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
                blend<Sums, Grouped>(f, corners, k, y + 3 * k);
            else
                y[3 * k] = y[3 * k + 1] = y[3 * k + 2] = 0.0f;  // gives the value 0, not counted
        }
        detail::from_space_n<kFused>(space, y, values, 3 * m, clamped);
        for (std::size_t k = 0; k < m; ++k) out[start + k] = {values[3 * k], values[3 * k + 1], values[3 * k + 2]};
    }
}

// A kernel's layout and grouping as one type: BRDFZ_HWY_BUILDS takes one template argument.
template <FactorLayout L, bool Grouped>
struct Shape {
    static constexpr FactorLayout kLayout = L;
    static constexpr bool kGrouped = Grouped;
};

}  // namespace
}  // namespace brdfz
#endif  // BRDFZ_REPR_FACTORED_EVAL_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "repr/factored_eval.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "factor_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::HWY_NAMESPACE {

// The kernel for the target, with brdfz::runtime's sums for the target, so both give the same bits
// (factored.h). Single-pair eval runs the same build as the batch.
template <typename S>
[[gnu::flatten]] void EvalPairs(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo, Rgb* out,
                                std::size_t n, std::uint64_t& clamped) {
    eval_pairs<runtime::kernels::HWY_NAMESPACE::FactorLanes, S::kLayout, S::kGrouped>(f, space, wi, wo, out, n,
                                                                                       clamped);
}

}  // namespace brdfz::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace brdfz {
namespace {

template <FactorLayout L, bool Grouped>
void eval_kernel(detail::Simd simd, const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo, Rgb* out,
                 std::size_t n, std::uint64_t& clamped) {
    using S = Shape<L, Grouped>;
    static const auto builds = BRDFZ_HWY_BUILDS(EvalPairs<S>);
    builds.at(simd)(f, space, wi, wo, out, n, clamped);
}

}  // namespace

void detail::eval_factors(Simd simd, FactorLayout layout, const FactorView& f, FactorSpace space, const Vec3* wi,
                          const Vec3* wo, Rgb* out, std::size_t n, std::uint64_t& clamped) {
    const bool h = layout == FactorLayout::HxDP;
    const auto kernel = f.grouped ? (h ? eval_kernel<FactorLayout::HxDP, true> : eval_kernel<FactorLayout::HDxP, true>)
                                  : (h ? eval_kernel<FactorLayout::HxDP, false> : eval_kernel<FactorLayout::HDxP, false>);
    kernel(simd, f, space, wi, wo, out, n, clamped);
}

}  // namespace brdfz
#endif  // HWY_ONCE
