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
#include <cstring>

#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/layout.h"

namespace brdfz::runtime::kernels {

struct FactorView {
    Grid grid;
    int layout = layout::kLayoutHxDP;
    int space = layout::kSpaceLog;
    // Rows of U and V `width` floats apart, a multiple of 4 with zeros beyond the components, and each
    // channel's weight of every column in `mix` (3 × width): the colour weights of shared factors; for
    // separate ones 1 on the channel's own components (at ch·rank + j, or at 4·ch + j for rank 3 and 4,
    // the core's grouped rows) and 0 elsewhere.
    std::size_t width = 4;
    const float* u = nullptr;
    const float* v = nullptr;
    const float* mix = nullptr;
    float ceiling[3] = {0, 0, 0};  // the data's largest value per channel, in the transform space
};

// Four floats in one SSE2 or NEON register where the compiler has vector types (GCC, Clang), an array
// elsewhere: written lane by lane, compilers vectorise the blends across steps instead, with shuffles.
#if defined(__GNUC__)
using Float4 = float __attribute__((vector_size(16)));
#else
struct Float4 {
    float lane[4];
    float operator[](int l) const { return lane[l]; }
    friend Float4 operator+(Float4 a, Float4 b) { return {{a.lane[0] + b.lane[0], a.lane[1] + b.lane[1], a.lane[2] + b.lane[2], a.lane[3] + b.lane[3]}}; }
    friend Float4 operator*(Float4 a, Float4 b) { return {{a.lane[0] * b.lane[0], a.lane[1] * b.lane[1], a.lane[2] * b.lane[2], a.lane[3] * b.lane[3]}}; }
};
#endif
inline Float4 load4(const float* p) {
    Float4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
inline Float4 splat4(float x) { return Float4{x, x, x, x}; }

// The channel sums y[3] of the factor products at the blend's rows and columns: NR rows of U and NC of V
// (2 and 4 in the layout h_dp, 4 and 2 in hd_p), fixed at compile time so that the blends unroll.
// Four columns a step, each channel's four sums kept apart and added pairwise at the end; padded
// columns add exact zeros.
template <int NR, int NC>
inline void factored_sums(const FactorView& f, const int* rows, const float* rw, const int* cols, const float* cw, float y[3]) {
    const std::size_t w = f.width;
    const float* u[NR];
    const float* v[NC];
    Float4 ru[NR], cv[NC];
    for (int r = 0; r < NR; ++r) u[r] = f.u + static_cast<std::size_t>(rows[r]) * w, ru[r] = splat4(rw[r]);
    for (int q = 0; q < NC; ++q) v[q] = f.v + static_cast<std::size_t>(cols[q]) * w, cv[q] = splat4(cw[q]);
    Float4 acc[3] = {splat4(0.0f), splat4(0.0f), splat4(0.0f)};
    for (std::size_t j = 0; j < w; j += 4) {
        Float4 a = ru[0] * load4(u[0] + j), b = cv[0] * load4(v[0] + j);
        for (int r = 1; r < NR; ++r) a = a + ru[r] * load4(u[r] + j);
        for (int q = 1; q < NC; ++q) b = b + cv[q] * load4(v[q] + j);
        const Float4 p = a * b;
        for (int ch = 0; ch < 3; ++ch) acc[ch] = acc[ch] + load4(f.mix + ch * w + j) * p;
    }
    for (int ch = 0; ch < 3; ++ch) y[ch] = (acc[ch][0] + acc[ch][1]) + (acc[ch][2] + acc[ch][3]);
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
