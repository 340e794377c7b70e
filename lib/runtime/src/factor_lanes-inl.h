// The factored eval's sums (brdfz/runtime/kernels/factored.h, factor_sums_reference: their order and
// what they compute) in Highway vectors, for one target: W = factor_lanes(level) floats a step, fused
// multiply-adds where factor_fused(level) says so, so every build gives the reference's bits. On a
// one-lane target (SCALAR) the reference itself runs.
//
// Highway's per-target header convention: include it after hwy/highway.h in a file that
// hwy/foreach_target.h compiles once per target; it defines FactorLanes in that target's namespace, the
// sums policy of the core's kernel (lib/src/repr/factored_eval.cpp) and the runtime's
// (lib/runtime/src/factored_calls.cpp).
#if defined(BRDFZ_FACTOR_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef BRDFZ_FACTOR_LANES_INL_H_
#undef BRDFZ_FACTOR_LANES_INL_H_
#else
#define BRDFZ_FACTOR_LANES_INL_H_
#endif

#include <algorithm>
#include <cstddef>

#include <hwy/highway.h>

#include "brdfz/runtime/kernels/factored.h"
#include "hwy_dispatch.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::runtime::kernels::HWY_NAMESPACE {

struct FactorLanes {
    static constexpr int kLanes = static_cast<int>(factor_lanes(level_of(HWY_TARGET)));
    static constexpr bool kFused = factor_fused(level_of(HWY_TARGET));

    // Not marked always-inline: eval_factored, which calls it, is compiled for no target, and its
    // callers, compiled for this one, flatten it.
    template <bool Grouped, int NR, int NC, typename View>
    static void sums(const View& f, const int* rows, const float* rw, const int* cols, const float* cw, float y[3]) {
#if HWY_TARGET == HWY_SCALAR
        factor_sums_reference<kLanes, kFused, Grouped, NR, NC>(f, rows, rw, cols, cw, y);
#else
        lane_sums<kLanes, Grouped, NR, NC>(f, rows, rw, cols, cw, y);
#endif
    }

#if HWY_TARGET != HWY_SCALAR
    template <int W, bool Grouped, int NR, int NC, typename View>
    HWY_INLINE static void lane_sums(const View& f, const int* rows, const float* rw, const int* cols, const float* cw,
                                     float y[3]) {
        namespace hn = hwy::HWY_NAMESPACE;
        const hn::FixedTag<float, W> d;
        const float* u[NR];
        const float* v[NC];
        for (int r = 0; r < NR; ++r) u[r] = f.u + static_cast<std::size_t>(rows[r]) * f.width;
        for (int q = 0; q < NC; ++q) v[q] = f.v + static_cast<std::size_t>(cols[q]) * f.width;
        // The products at columns [j, j + W).
        const auto product = [&](std::size_t j) HWY_ATTR {
            auto a = hn::Mul(hn::Set(d, rw[0]), hn::LoadU(d, u[0] + j));
            auto b = hn::Mul(hn::Set(d, cw[0]), hn::LoadU(d, v[0] + j));
            for (int r = 1; r < NR; ++r) a = mul_add(hn::Set(d, rw[r]), hn::LoadU(d, u[r] + j), a);
            for (int q = 1; q < NC; ++q) b = mul_add(hn::Set(d, cw[q]), hn::LoadU(d, v[q] + j), b);
            return hn::Mul(a, b);
        };
        float s[3];
        if constexpr (Grouped) {
            // The 3 groups of 4 floats, in whole steps.
            constexpr std::size_t kSteps = (12 + W - 1) / W;
            float g[kSteps * W];
            for (std::size_t step = 0; step < kSteps; ++step) hn::StoreU(product(step * W), d, g + step * W);
            const hn::FixedTag<float, 4> d4;
            pairwise_sums(hn::LoadU(d4, g), hn::LoadU(d4, g + 4), hn::LoadU(d4, g + 8), s);
        } else {
            auto acc0 = hn::Zero(d), acc1 = acc0, acc2 = acc0;
            for (std::size_t j = 0; j < f.width; j += W) {
                const auto p = product(j);
                acc0 = mul_add(hn::LoadU(d, f.mix + j), p, acc0);
                acc1 = mul_add(hn::LoadU(d, f.mix + f.width + j), p, acc1);
                acc2 = mul_add(hn::LoadU(d, f.mix + 2 * f.width + j), p, acc2);
            }
            if constexpr (W == 8)
                pairwise_sums(halves_added(acc0), halves_added(acc1), halves_added(acc2), s);
            else
                pairwise_sums(acc0, acc1, acc2, s);
        }
        // At most the data's largest value: bins without data can reconstruct far beyond it (factor.h).
        for (int ch = 0; ch < 3; ++ch) y[ch] = std::min(s[ch], f.ceiling[ch]);
    }

    template <class V>
    HWY_INLINE static V mul_add(V m, V x, V a) {
        namespace hn = hwy::HWY_NAMESPACE;
        if constexpr (kFused)
            return hn::MulAdd(m, x, a);
        else
            return hn::Add(hn::Mul(m, x), a);
    }

    // The lanes [0, 4) plus the lanes [4, 8) of an 8-lane vector.
    template <class V>
    HWY_INLINE static auto halves_added(V x) {
        namespace hn = hwy::HWY_NAMESPACE;
        const hn::FixedTag<float, 4> d4;
        return hn::Add(hn::LowerHalf(d4, x), hn::UpperHalf(d4, x));
    }

    // Each 4-lane vector's pairwise sum ((x0 + x1) + (x2 + x3)), as adds of its even and odd lanes.
    template <class V>
    HWY_INLINE static void pairwise_sums(V a0, V a1, V a2, float s[3]) {
        namespace hn = hwy::HWY_NAMESPACE;
        const hn::FixedTag<float, 4> d4;
        // (x0 + x1, x2 + x3, y0 + y1, y2 + y3)
        const auto hadd = [d4](V x, V y) HWY_ATTR { return hn::Add(hn::ConcatEven(d4, y, x), hn::ConcatOdd(d4, y, x)); };
        float t[4];
        hn::StoreU(hadd(hadd(a0, a1), hadd(a2, a2)), d4, t);
        s[0] = t[0], s[1] = t[1], s[2] = t[2];
    }
#endif
};

}  // namespace brdfz::runtime::kernels::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // BRDFZ_FACTOR_LANES_INL_H_
