// A factored BRDF's evaluation (the core's FactoredBrdf, brdfz/repr/factored.h, says what the factors
// mean), written once for the core's batch kernel (lib/src/repr/factored_eval.cpp) and brdfz::runtime:
// the factor rows blended in float at a pair's interpolation corners, their products summed per channel
// with the colour mix, clamped to the data's ceiling, and the transform space inverted.
//
// W floats a step: 4 in the baseline build, 8 in the AVX2 and AVX-512 ones, whose sources are compiled
// with FMA contraction (the only kernels that are): the sums of shared-colour svd factors cancel (terms
// up to 10^5 times their sum), so those builds differ from the baseline by more than float rounding of
// the value, but the library and the runtime, running the same build, agree to the bit.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>

#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/kernels/simd.h"
#include "brdfz/runtime/layout.h"

namespace brdfz::runtime::kernels {

// Floats per blend step of a level's build; factor rows are zero-padded to a multiple of it.
constexpr std::size_t factor_lanes(Simd s) { return s >= Simd::Avx2Fma ? 8 : 4; }

struct FactorView {
    Grid grid;
    int layout = layout::kLayoutHxDP;
    int space = layout::kSpaceLog;
    // Rows of U and V `width` floats apart, a multiple of the build's lanes with zeros beyond the
    // components, and each channel's weight of every column in `mix` (3 × width): the colour weights of
    // shared factors; for separate ones 1 on the channel's own components (at ch·rank + j) and 0
    // elsewhere. Grouped (separate colour of rank 3 or 4): channel c's components from float 4c, so each
    // channel is one group of 4 floats, summed without the mix.
    std::size_t width = 4;
    bool grouped = false;
    const float* u = nullptr;
    const float* v = nullptr;
    const float* mix = nullptr;
    float ceiling[3] = {0, 0, 0};  // the data's largest value per channel, in the transform space
};

// W floats in one SSE2, AVX or NEON register where the compiler has vector types (GCC, Clang), an array
// elsewhere. Only inside always-inlined code: no such vector crosses a call, so the ABI note GCC gives
// for 8-float vectors outside AVX code does not apply.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
template <int W>
struct FloatLanesOf;
template <>
struct FloatLanesOf<4> {
    typedef float type __attribute__((vector_size(16)));
};
template <>
struct FloatLanesOf<8> {
    typedef float type __attribute__((vector_size(32)));
};
template <int W>
using FloatLanes = typename FloatLanesOf<W>::type;
#else
template <int W>
struct FloatLanes {
    float lane[W];
    float operator[](int l) const { return lane[l]; }
    friend FloatLanes operator*(float s, FloatLanes a) {
        for (float& x : a.lane) x *= s;
        return a;
    }
    friend FloatLanes operator*(FloatLanes a, const FloatLanes& b) {
        for (int l = 0; l < W; ++l) a.lane[l] *= b.lane[l];
        return a;
    }
    FloatLanes& operator+=(const FloatLanes& b) {
        for (int l = 0; l < W; ++l) lane[l] += b.lane[l];
        return *this;
    }
};
#endif

template <int W>
[[gnu::always_inline]] inline FloatLanes<W> load_lanes(const float* p) {
    FloatLanes<W> v;
    std::memcpy(&v, p, sizeof v);  // unaligned: one movups
    return v;
}

// The lane sums of three vectors, each pairwise: ((x0 + x1) + (x2 + x3)), the halves of 8 lanes added
// first. With vector types, as adds of shuffled vectors (a scalar sum per vector takes three times the
// instructions).
#if defined(__GNUC__)
[[gnu::always_inline]] inline void lane_sums(const FloatLanes<4> (&a)[3], float s[3]) {
    const auto hadd = [](FloatLanes<4> x, FloatLanes<4> y) {
        return __builtin_shufflevector(x, y, 0, 2, 4, 6) + __builtin_shufflevector(x, y, 1, 3, 5, 7);
    };
    const FloatLanes<4> t = hadd(hadd(a[0], a[1]), hadd(a[2], a[2]));
    s[0] = t[0], s[1] = t[1], s[2] = t[2];
}
[[gnu::always_inline]] inline void lane_sums(const FloatLanes<8> (&a)[3], float s[3]) {
    FloatLanes<4> h[3];
    for (int i = 0; i < 3; ++i)
        h[i] = __builtin_shufflevector(a[i], a[i], 0, 1, 2, 3) + __builtin_shufflevector(a[i], a[i], 4, 5, 6, 7);
    lane_sums(h, s);
}
#else
template <int W>
inline void lane_sums(const FloatLanes<W> (&a)[3], float s[3]) {
    for (int i = 0; i < 3; ++i) {
        float h[4];
        for (int l = 0; l < 4; ++l) h[l] = W == 8 ? a[i][l] + a[i][l + 4] : a[i][l];
        s[i] = (h[0] + h[1]) + (h[2] + h[3]);
    }
}
#endif

// The channel values y[3], in the transform space, at a pair's corners: NR rows of U and NC of V (2 and
// 4 in the layout h_dp, 4 and 2 in hd_p) and their weights, fixed at compile time so that the blends
// unroll. y_c = Σ_j mix_cj · (Σ_r rw_r U[r][j]) · (Σ_c cw_c V[c][j]), clamped to the ceiling; padded
// columns add exact zeros. The float sums are within ~1e-7 of the factors' magnitude, as the float32
// factors themselves.
// View: FactorView, or the core's view of its own padded copies (the same members).
template <int W, bool Grouped, int NR, int NC, typename View>
[[gnu::always_inline]] inline void factor_sums(const View& f, const int* rows, const float* rw, const int* cols,
                                               const float* cw, float y[3]) {
    using V = FloatLanes<W>;
    const float* u[NR];
    const float* v[NC];
    for (int r = 0; r < NR; ++r) u[r] = f.u + static_cast<std::size_t>(rows[r]) * f.width;
    for (int q = 0; q < NC; ++q) v[q] = f.v + static_cast<std::size_t>(cols[q]) * f.width;
    // p = the product at columns [j, j + W). By reference: a vector returned by value would cross a call
    // in the ABI of the level's instruction set.
    const auto product = [&](std::size_t j, V& p) {
        V a = rw[0] * load_lanes<W>(u[0] + j), b = cw[0] * load_lanes<W>(v[0] + j);
        for (int r = 1; r < NR; ++r) a += rw[r] * load_lanes<W>(u[r] + j);
        for (int q = 1; q < NC; ++q) b += cw[q] * load_lanes<W>(v[q] + j);
        p = a * b;
    };
    float s[3];
    if constexpr (Grouped) {
        // The 3 groups of 4 floats, in whole steps.
        constexpr std::size_t kSteps = (12 + W - 1) / W;
        float g[kSteps * W];
        for (std::size_t step = 0; step < kSteps; ++step) {
            V p;
            product(step * W, p);
            std::memcpy(g + step * W, &p, sizeof p);
        }
        const FloatLanes<4> groups[3] = {load_lanes<4>(g), load_lanes<4>(g + 4), load_lanes<4>(g + 8)};
        lane_sums(groups, s);
    } else {
        V acc[3] = {};
        for (std::size_t j = 0; j < f.width; j += W) {
            V p;
            product(j, p);
            for (int ch = 0; ch < 3; ++ch) acc[ch] += load_lanes<W>(f.mix + ch * f.width + j) * p;
        }
        lane_sums(acc, s);
    }
    // At most the data's largest value: bins without data can reconstruct far beyond it (factor.h).
    for (int ch = 0; ch < 3; ++ch) y[ch] = std::min(s[ch], f.ceiling[ch]);
}
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

// A pair's corners as factor rows and columns with their weights: the 2-D axis' four (outer span a,
// inner span b, `inner` samples along b) and the 1-D axis' two.
inline void factor_corners_2d(const Span& a, const Span& b, int inner, int idx[4], float w[4]) {
    idx[0] = a.i0 * inner + b.i0, idx[1] = a.i0 * inner + b.i1, idx[2] = a.i1 * inner + b.i0, idx[3] = a.i1 * inner + b.i1;
    w[0] = static_cast<float>((1.0 - a.t) * (1.0 - b.t)), w[1] = static_cast<float>((1.0 - a.t) * b.t);
    w[2] = static_cast<float>(a.t * (1.0 - b.t)), w[3] = static_cast<float>(a.t * b.t);
}
inline void factor_corners_1d(const Span& a, int idx[2], float w[2]) {
    idx[0] = a.i0, idx[1] = a.i1, w[0] = static_cast<float>(1.0 - a.t), w[1] = static_cast<float>(a.t);
}

// A transform-space value y (clamped to the ceiling) as the BRDF's value: reconstructions below 0 are 0.
inline double from_factor_space(int space, float y) {
    const float pos = y > 0.0f ? y : 0.0f;
    return space == layout::kSpaceLog ? expm1_nonneg_f(pos) : space == layout::kSpaceCbrt ? static_cast<double>(pos) * pos * pos : pos;
}

// f for a pair above the horizon, in the build of W lanes (the view's width a multiple of W).
template <int W>
[[gnu::always_inline]] inline void eval_factored(const FactorView& f, const Vec3& wi, const Vec3& wo, double out[3]) {
    const Grid& g = f.grid;
    BinCoords c = fast_bin_coords(g, wi, wo);
    if (!(c.up <= g.n_phi_d)) c = bin_coords(g, wi, wo);  // kIllConditioned or NaN
    const double off = g.sample_offset();
    const Span h = clamped_span(c.uh - off, g.n_theta_h), d = clamped_span(c.ud - off, g.n_theta_d),
               p = phi_d_span(g, c.up - off);
    int rows[4], cols[4];
    float rw[4], cw[4], y[3];
    if (f.layout == layout::kLayoutHxDP) {
        factor_corners_1d(h, rows, rw);
        factor_corners_2d(d, p, g.n_phi_d, cols, cw);
        f.grouped ? factor_sums<W, true, 2, 4>(f, rows, rw, cols, cw, y) : factor_sums<W, false, 2, 4>(f, rows, rw, cols, cw, y);
    } else {
        factor_corners_2d(h, d, g.n_theta_d, rows, rw);
        factor_corners_1d(p, cols, cw);
        f.grouped ? factor_sums<W, true, 4, 2>(f, rows, rw, cols, cw, y) : factor_sums<W, false, 4, 2>(f, rows, rw, cols, cw, y);
    }
    for (int ch = 0; ch < 3; ++ch) out[ch] = from_factor_space(f.space, y[ch]);
}

}  // namespace brdfz::runtime::kernels
