// A factored BRDF's evaluation (the core's FactoredBrdf, brdfz/repr/factored.h, says what the factors
// mean), written once for the core's batch kernel (lib/src/repr/factored_eval.cpp) and brdfz::runtime:
// the factor rows blended in float at a pair's interpolation corners, their products summed per channel
// with the colour mix, clamped to the data's ceiling, and the transform space inverted.
//
// The sums are the costly part: factor_sums_reference below is their scalar reference, and each
// Highway target's build (lib/runtime/src/factor_lanes-inl.h) gives its bits. W floats a step: 8 in
// x86-64's AVX2 and AVX-512 builds, which fuse their multiply-adds, 4 elsewhere. The sums of
// shared-colour svd factors cancel (terms up to 10^5 times their sum), so the fused builds differ from
// the others by more than float rounding of the value; every build without fusion, ARM64's too, gives
// the same bits, and the library and the runtime, running the same build, agree to the bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/kernels/simd.h"
#include "brdfz/runtime/layout.h"

namespace brdfz::runtime::kernels {

// Floats per blend step of a level's build (one 256-bit vector in x86-64's AVX2 and AVX-512 builds;
// ARM64's SVE vectors may be 128 bits); factor rows are zero-padded to a multiple of it.
constexpr std::size_t factor_lanes([[maybe_unused]] Simd s) {
#if defined(__x86_64__) || defined(_M_X64)
    return s >= Simd::Avx2Fma ? 8 : 4;
#else
    return 4;
#endif
}
// Whether a level's build fuses the eval's multiply-adds (the sums, and through math.h's madd the
// coordinates and the inverse transform): x86-64's builds whose CPU test includes FMA.
constexpr bool factor_fused([[maybe_unused]] Simd s) {
#if defined(__x86_64__) || defined(_M_X64)
    return s >= Simd::Avx2Fma;
#else
    return false;
#endif
}

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

// The channel values y[3], in the transform space, at a pair's corners: NR rows of U and NC of V (2 and
// 4 in the layout h_dp, 4 and 2 in hd_p) and their weights, fixed at compile time so that the blends
// unroll. y_c = Σ_j mix_cj · (Σ_r rw_r U[r][j]) · (Σ_c cw_c V[c][j]), clamped to the ceiling; padded
// columns add exact zeros. The float sums are within ~1e-7 of the factors' magnitude, as the float32
// factors themselves.
//
// The reference's order, which the vector builds keep: W lanes, lane l summing the columns l, l + W, ...
// (Fused: each product-and-sum one fused multiply-add); then each lane set summed pairwise,
// ((x0 + x1) + (x2 + x3)), the halves of 8 lanes added first. Grouped (separate colour of rank 3 or 4):
// channel c's products are the 4 floats from 4c, summed without the mix.
// View: FactorView, or the core's view of its own padded copies (the same members).
template <int W, bool Fused, bool Grouped, int NR, int NC, typename View>
inline void factor_sums_reference(const View& f, const int* rows, const float* rw, const int* cols, const float* cw,
                                  float y[3]) {
    const auto mul_add = [](float m, float x, float a) { return Fused ? std::fma(m, x, a) : m * x + a; };
    // The product at column j.
    const auto product = [&](std::size_t j) {
        const float* u0 = f.u + static_cast<std::size_t>(rows[0]) * f.width;
        const float* v0 = f.v + static_cast<std::size_t>(cols[0]) * f.width;
        float a = rw[0] * u0[j], b = cw[0] * v0[j];
        for (int r = 1; r < NR; ++r) a = mul_add(rw[r], f.u[static_cast<std::size_t>(rows[r]) * f.width + j], a);
        for (int q = 1; q < NC; ++q) b = mul_add(cw[q], f.v[static_cast<std::size_t>(cols[q]) * f.width + j], b);
        return a * b;
    };
    const auto pairwise = [](const float* x) { return (x[0] + x[1]) + (x[2] + x[3]); };
    float s[3];
    if constexpr (Grouped) {
        for (int ch = 0; ch < 3; ++ch) {
            float g[4];
            for (int l = 0; l < 4; ++l) g[l] = product(4 * static_cast<std::size_t>(ch) + l);
            s[ch] = pairwise(g);
        }
    } else {
        for (int ch = 0; ch < 3; ++ch) {
            float acc[W] = {};
            for (std::size_t j = 0; j < f.width; j += W)
                for (int l = 0; l < W; ++l) acc[l] = mul_add(f.mix[ch * f.width + j + l], product(j + l), acc[l]);
            if constexpr (W == 8)
                for (int l = 0; l < 4; ++l) acc[l] += acc[l + 4];
            s[ch] = pairwise(acc);
        }
    }
    // At most the data's largest value: bins without data can reconstruct far beyond it (factor.h).
    for (int ch = 0; ch < 3; ++ch) y[ch] = std::min(s[ch], f.ceiling[ch]);
}

// factor_sums_reference as a sums policy, which eval_factored and the core's kernel take: this one, or
// a target's vector build (lib/runtime/src/factor_lanes-inl.h, FactorLanes).
template <int W, bool Fused>
struct ReferenceSums {
    static constexpr int kLanes = W;
    static constexpr bool kFused = Fused;
    template <bool Grouped, int NR, int NC, typename View>
    static void sums(const View& f, const int* rows, const float* rw, const int* cols, const float* cw, float y[3]) {
        factor_sums_reference<W, Fused, Grouped, NR, NC>(f, rows, rw, cols, cw, y);
    }
};

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
template <bool Fused>
inline double from_factor_space(int space, float y) {
    const float pos = y > 0.0f ? y : 0.0f;
    return space == layout::kSpaceLog ? expm1_nonneg_f<Fused>(pos) : space == layout::kSpaceCbrt ? static_cast<double>(pos) * pos * pos : pos;
}

// f for a pair above the horizon, with a sums policy (ReferenceSums, or a target's FactorLanes; the
// view's width a multiple of its kLanes), whose kFused the coordinates and the inverse transform take too.
template <typename Sums>
[[gnu::always_inline]] inline void eval_factored(const FactorView& f, const Vec3& wi, const Vec3& wo, double out[3]) {
    const Grid& g = f.grid;
    constexpr bool kFused = Sums::kFused;
    BinCoords c = fast_bin_coords<ThetaHAxes::Any, kFused>(g, wi, wo);
    if (!(c.up <= g.n_phi_d)) c = bin_coords(g, wi, wo);  // kIllConditioned or NaN
    const double off = g.sample_offset();
    const Span h = clamped_span(c.uh - off, g.n_theta_h), d = clamped_span(c.ud - off, g.n_theta_d),
               p = phi_d_span(g, c.up - off);
    int rows[4], cols[4];
    float rw[4], cw[4], y[3];
    if (f.layout == layout::kLayoutHxDP) {
        factor_corners_1d(h, rows, rw);
        factor_corners_2d(d, p, g.n_phi_d, cols, cw);
        f.grouped ? Sums::template sums<true, 2, 4>(f, rows, rw, cols, cw, y) : Sums::template sums<false, 2, 4>(f, rows, rw, cols, cw, y);
    } else {
        factor_corners_2d(h, d, g.n_theta_d, rows, rw);
        factor_corners_1d(p, cols, cw);
        f.grouped ? Sums::template sums<true, 4, 2>(f, rows, rw, cols, cw, y) : Sums::template sums<false, 4, 2>(f, rows, rw, cols, cw, y);
    }
    for (int ch = 0; ch < 3; ++ch) out[ch] = from_factor_space<kFused>(f.space, y[ch]);
}

}  // namespace brdfz::runtime::kernels
