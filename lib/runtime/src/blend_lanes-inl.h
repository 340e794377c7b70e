// blend_linear (brdfz/runtime/kernels/grid.h, the scalar reference) across channels in Highway vectors
// of doubles, for one target: the three channels and a spare lane in one vector of four where the
// target has 256-bit vectors (AVX2, AVX-512), in two vectors of two elsewhere (SSE4, NEON, SVE), and
// the reference itself on a one-lane target (SCALAR). Each channel's arithmetic is the reference's (the
// same products, the same order of sums, no fused multiply-add), so every build gives its bits.
//
// Highway's per-target header convention: include it after hwy/highway.h in a file that
// hwy/foreach_target.h compiles once per target; it defines BlendLanes in that target's namespace, a
// policy the table kernels take (lib/src/detail/table_lookup.h, lib/runtime/src/runtime.cpp).
#if defined(BRDFZ_BLEND_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef BRDFZ_BLEND_LANES_INL_H_
#undef BRDFZ_BLEND_LANES_INL_H_
#else
#define BRDFZ_BLEND_LANES_INL_H_
#endif

#include <cstddef>

#include <hwy/highway.h>

#include "brdfz/runtime/kernels/grid.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::runtime::kernels::HWY_NAMESPACE {

// blend is not marked always-inline: the table kernels that call it are compiled for no target, and
// their callers, compiled for this one, flatten them.
struct BlendLanes {
    template <typename G, typename Values>
    static void blend(const G& g, const Values& values, const Corners& k, double f[3]) {
#if HWY_TARGET == HWY_SCALAR
        blend_linear(g, values, k, f);
#elif !HWY_HAVE_SCALABLE && HWY_MAX_BYTES >= 32
        const hwy::HWY_NAMESPACE::FixedTag<double, 4> d;
        auto sum = hwy::HWY_NAMESPACE::Zero(d), wsum = sum;
        for_each_corner(g, k, [&](std::size_t bin, double w) HWY_ATTR {
            add_corner(hwy::HWY_NAMESPACE::Set(d, w), load_bin(d, values, bin, 0), sum, wsum);
        });
        double q[4];
        store_quotients(d, sum, wsum, q);
        for (int c = 0; c < 3; ++c) f[c] = q[c];
#else
        const hwy::HWY_NAMESPACE::FixedTag<double, 2> d;
        auto sum0 = hwy::HWY_NAMESPACE::Zero(d), wsum0 = sum0, sum1 = sum0, wsum1 = sum0;
        for_each_corner(g, k, [&](std::size_t bin, double w) HWY_ATTR {
            const auto wv = hwy::HWY_NAMESPACE::Set(d, w);
            add_corner(wv, load_bin(d, values, bin, 0), sum0, wsum0);
            add_corner(wv, load_bin(d, values, bin, 2), sum1, wsum1);
        });
        double q[4];
        store_quotients(d, sum0, wsum0, q);
        store_quotients(d, sum1, wsum1, q + 2);
        for (int c = 0; c < 3; ++c) f[c] = q[c];
#endif
    }

#if HWY_TARGET != HWY_SCALAR
    // A bin's channels from `first` as doubles, as many as D holds (beyond the third, unused content).
    // Bins of three floats padded to four load as one vector (grid.h, FloatBins); others decode to
    // scalars, combined in registers: a vector loaded from their stores would wait for them (a load
    // spanning several stores is not forwarded from them).
    template <class D, typename Values>
    HWY_INLINE static auto load_bin(D d, const Values& values, std::size_t bin, int first) {
        namespace hn = hwy::HWY_NAMESPACE;
        if constexpr (FloatBins<Values>::value) {
            return hn::PromoteTo(d, hn::LoadU(hn::Rebind<float, D>(), values.floats(bin) + first));
        } else {
            float v[3];
            values.load(bin, v);
            const double x[4] = {v[0], v[1], v[2], 0.0};
            return combined(d, x + first);
        }
    }
    template <class D>
    HWY_INLINE static hwy::HWY_NAMESPACE::Vec<D> combined(D d, const double* x) {
        namespace hn = hwy::HWY_NAMESPACE;
#if HWY_HAVE_SCALABLE
        // Two lanes: SVE's tags have no one-lane halves to combine.
        return hn::InterleaveLower(d, hn::Set(d, x[0]), hn::Set(d, x[1]));
#else
        if constexpr (hn::MaxLanes(d) == 1) {
            return hn::Set(d, x[0]);
        } else {
            const hn::Half<D> dh;
            return hn::Combine(d, combined(dh, x + hn::MaxLanes(dh)), combined(dh, x));
        }
#endif
    }

    // Invalid samples are NaN: they contribute neither value nor weight.
    template <class V>
    HWY_INLINE static void add_corner(V w, V x, V& sum, V& wsum) {
        namespace hn = hwy::HWY_NAMESPACE;
        const auto ok = hn::Eq(x, x);
        sum = hn::Add(sum, hn::IfThenElseZero(ok, hn::Mul(w, x)));
        wsum = hn::Add(wsum, hn::IfThenElseZero(ok, w));
    }

    // sum / wsum where some weight was valid, else 0, into q (as many lanes as D holds).
    template <class D, class V>
    HWY_INLINE static void store_quotients(D d, V sum, V wsum, double* q) {
        namespace hn = hwy::HWY_NAMESPACE;
        hn::StoreU(hn::IfThenElseZero(hn::Gt(wsum, hn::Zero(d)), hn::Div(sum, wsum)), d, q);
    }
#endif
};

}  // namespace brdfz::runtime::kernels::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // BRDFZ_BLEND_LANES_INL_H_
