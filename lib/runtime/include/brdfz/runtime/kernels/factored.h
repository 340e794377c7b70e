// A factored BRDF's evaluation for one pair (the core's FactoredBrdf, brdfz/repr/factored.h, says what
// the factors mean): the pair's bin coordinates and interpolation corners (kernels/grid.h), the factor
// rows blended in float at those corners, their products summed per channel with the colour mix,
// clamped to the data's ceiling, and the transform space inverted. In the order of the core's batch
// kernel's SSE2 build (lib/src/repr/factored_eval.cpp: four lanes of components, each lane summed in
// turn, then the lanes pairwise), so that the runtime gives that build's bits: the sums of
// shared-colour svd factors cancel (terms up to 10^5 times their sum), and another order moves a value
// by more than float rounding of the value. The library's AVX builds (eight lanes, fused
// multiply-adds) differ from its SSE2 build by that much too.
#pragma once

#include <algorithm>
#include <cstddef>

#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/layout.h"

namespace brdfz::runtime::kernels {

struct FactorView {
    Grid grid;
    int layout = layout::kLayoutHxDP;
    int space = layout::kSpaceLog;
    bool shared = false;       // one U and V for all channels, with colour weights
    int rank = 1;
    const float* u = nullptr;  // rows × m, m = rank (shared) or 3·rank (separate: channel c's from c·rank)
    const float* v = nullptr;  // columns × m
    const float* colour = nullptr;  // 3 × rank (shared)
    float ceiling[3] = {0, 0, 0};   // the data's largest value per channel, in the transform space
    int m() const { return shared ? rank : 3 * rank; }
};

// The channel sums y[3] of the factor products at the blend's rows and columns: NR rows of U and NC of V
// (2 and 4 in the layout h_dp, 4 and 2 in hd_p), fixed at compile time so that the blends unroll.
template <int NR, int NC>
inline void factored_sums(const FactorView& f, const int* rows, const float* rw, const int* cols, const float* cw, float y[3]) {
    const int m = f.m();
    // Component j's product: the blend of its U rows times the blend of its V rows (0 in the padding
    // the core's rows have beyond m).
    const auto product = [&](int j) {
        if (j >= m) return 0.0f;
        float a = rw[0] * f.u[static_cast<std::size_t>(rows[0]) * m + j];
        float b = cw[0] * f.v[static_cast<std::size_t>(cols[0]) * m + j];
        for (int r = 1; r < NR; ++r) a += rw[r] * f.u[static_cast<std::size_t>(rows[r]) * m + j];
        for (int q = 1; q < NC; ++q) b += cw[q] * f.v[static_cast<std::size_t>(cols[q]) * m + j];
        return a * b;
    };
    if (!f.shared && (f.rank == 3 || f.rank == 4)) {
        // Each channel's components in a lane group of their own (the core's grouped rows).
        for (int ch = 0; ch < 3; ++ch) {
            float g[4];
            for (int l = 0; l < 4; ++l) g[l] = l < f.rank ? product(ch * f.rank + l) : 0.0f;
            y[ch] = (g[0] + g[1]) + (g[2] + g[3]);
        }
        return;
    }
    // Channel ch's weight of component j: its colour weight, or 1 for its own channel's components
    // (separate factors: channel ch's are j in [ch·rank, (ch + 1)·rank)); 0 in the padding.
    const auto mix = [&](int ch, int j) {
        if (j >= m) return 0.0f;
        if (f.shared) return f.colour[ch * f.rank + j];
        return j >= ch * f.rank && j < (ch + 1) * f.rank ? 1.0f : 0.0f;
    };
    // Lane l of channel ch sums components j ≡ l (mod 4) in order; twelve named sums rather than an
    // array indexed in the loop, which compilers keep in memory (a store-to-load chain per sum).
    float a00 = 0, a01 = 0, a02 = 0, a03 = 0, a10 = 0, a11 = 0, a12 = 0, a13 = 0, a20 = 0, a21 = 0, a22 = 0, a23 = 0;
    for (int j0 = 0; j0 < m; j0 += 4) {
        const float p0 = product(j0), p1 = product(j0 + 1), p2 = product(j0 + 2), p3 = product(j0 + 3);
        a00 += mix(0, j0) * p0, a01 += mix(0, j0 + 1) * p1, a02 += mix(0, j0 + 2) * p2, a03 += mix(0, j0 + 3) * p3;
        a10 += mix(1, j0) * p0, a11 += mix(1, j0 + 1) * p1, a12 += mix(1, j0 + 2) * p2, a13 += mix(1, j0 + 3) * p3;
        a20 += mix(2, j0) * p0, a21 += mix(2, j0 + 1) * p1, a22 += mix(2, j0 + 2) * p2, a23 += mix(2, j0 + 3) * p3;
    }
    y[0] = (a00 + a01) + (a02 + a03), y[1] = (a10 + a11) + (a12 + a13), y[2] = (a20 + a21) + (a22 + a23);
}

// f for a pair above the horizon.
inline void eval_factored(const FactorView& f, const Vec3& wi, const Vec3& wo, double out[3]) {
    const Grid& g = f.grid;
    BinCoords c = fast_bin_coords(g, wi, wo);
    if (!(c.up <= g.n_phi_d)) c = bin_coords(g, wi, wo);  // kIllConditioned or NaN
    const double off = g.sample_offset();
    const Span h = clamped_span(c.uh - off, g.n_theta_h), d = clamped_span(c.ud - off, g.n_theta_d),
               p = phi_d_span(g, c.up - off);
    // The rows of U and V to blend and their weights, in the float the core's kernel blends with.
    int rows[4], cols[4];
    float rw[4], cw[4];
    const auto pairs = [](const Span& a, const Span& b, int inner, int* idx, float* w) {
        idx[0] = a.i0 * inner + b.i0, idx[1] = a.i0 * inner + b.i1, idx[2] = a.i1 * inner + b.i0, idx[3] = a.i1 * inner + b.i1;
        w[0] = static_cast<float>((1.0 - a.t) * (1.0 - b.t)), w[1] = static_cast<float>((1.0 - a.t) * b.t);
        w[2] = static_cast<float>(a.t * (1.0 - b.t)), w[3] = static_cast<float>(a.t * b.t);
    };
    float y[3];
    if (f.layout == layout::kLayoutHxDP) {
        rows[0] = h.i0, rows[1] = h.i1, rw[0] = static_cast<float>(1.0 - h.t), rw[1] = static_cast<float>(h.t);
        pairs(d, p, g.n_phi_d, cols, cw);
        factored_sums<2, 4>(f, rows, rw, cols, cw, y);
    } else {
        pairs(h, d, g.n_theta_d, rows, rw);
        cols[0] = p.i0, cols[1] = p.i1, cw[0] = static_cast<float>(1.0 - p.t), cw[1] = static_cast<float>(p.t);
        factored_sums<4, 2>(f, rows, rw, cols, cw, y);
    }
    for (int ch = 0; ch < 3; ++ch) {
        const float q = std::min(y[ch], f.ceiling[ch]);
        const float pos = q > 0.0f ? q : 0.0f;  // svd reconstructions below 0 are 0
        out[ch] = f.space == layout::kSpaceLog    ? expm1_nonneg_f(pos)
                  : f.space == layout::kSpaceCbrt ? static_cast<double>(pos) * pos * pos
                                                  : pos;
    }
}

}  // namespace brdfz::runtime::kernels
