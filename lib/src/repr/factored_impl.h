// What the parts of FactoredBrdf share: the transform spaces, and the eval kernels' entry point. The
// kernels (factored_eval.cpp) and the factorisation on Eigen (factored_fit.cpp) are units of their own,
// so that a build compiles them side by side.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "brdfz/repr/factored.h"
#include "brdfz/runtime/kernels/factored.h"
#include "detail/fast_math.h"
#include "detail/simd.h"

namespace brdfz::detail {

// ---------------------------------------------------------------------------------------------
// Transform spaces


inline double to_space(FactorSpace s, double f) {
    switch (s) {
        case FactorSpace::Log: return std::log1p(f);
        case FactorSpace::Cbrt: return std::cbrt(f);
        default: return f;
    }
}

// The value for a reconstruction y (already at most the ceiling); y < 0 (possible for svd) gives 0.
// No libm call, so the loop below vectorises. A float y (eval's blend, ~1e-7 from exact already)
// takes the float expm1, a double y (reconstruct) the double one; the cube is in double, where the
// ceiling's cube cannot overflow. Fused: the float expm1 with fused multiply-adds (math.h, madd), in
// the eval builds that fuse their sums.
template <FactorSpace S, bool Fused = false, typename T>
inline double from_space(T y) {
    const T p = y > T(0) ? y : T(0);  // NaN cannot occur: factors are finite
    if constexpr (S == FactorSpace::Log) {
        if constexpr (std::is_same_v<T, float>)
            return expm1_nonneg_f<Fused>(p);
        else
            return expm1_nonneg(p);
    } else if constexpr (S == FactorSpace::Cbrt) {
        const double q = p;
        return q * q * q;
    } else {
        return p;
    }
}

// out[i] = the value of y[i], counting the negatives clamped (in a T: GCC vectorises that sum
// with the loop, not an integer one).
template <FactorSpace S, bool Fused, typename T>
void from_space_n(const T* y, double* out, std::size_t n, std::uint64_t& clamped) {
    T count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        count += y[i] < T(0) ? T(1) : T(0);
        out[i] = from_space<S, Fused>(y[i]);
    }
    clamped += static_cast<std::uint64_t>(count);
}

template <bool Fused = false, typename T>
void from_space_n(FactorSpace s, const T* y, double* out, std::size_t n, std::uint64_t& clamped) {
    switch (s) {
        case FactorSpace::Log: return from_space_n<FactorSpace::Log, Fused>(y, out, n, clamped);
        case FactorSpace::Cbrt: return from_space_n<FactorSpace::Cbrt, Fused>(y, out, n, clamped);
        default: return from_space_n<FactorSpace::Linear, Fused>(y, out, n, clamped);
    }
}

// ---------------------------------------------------------------------------------------------
// Evaluation

// Floats per blend step of each kernel; rows are zero-padded to a multiple of it.
using runtime::kernels::factor_lanes;

// The factors as evaluation reads them (FactoredBrdf's padded copies): rows `width` floats apart.
struct FactorView {
    const GridSpec& grid;
    std::size_t width;  // row_width() rounded up to the kernel's lanes, zero-padded
    const float* u;
    const float* v;
    const float* mix;       // 3 × width
    const float* ceiling;   // 3: max_value in the transform space, rounded to float
    bool prefetch_u, prefetch_v;  // prefetch that factor's rows (FactoredBrdf::eval_batch)
    bool grouped;                 // grouped_channels
};

// The batch kernel of the given build for the view's layout and channel grouping (grouped_channels):
// out[i] = f(wi[i], wo[i]), the reconstructions clamped below 0 counted in `clamped`.
void eval_factors(Simd simd, FactorLayout layout, const FactorView& f, FactorSpace space, const Vec3* wi,
                  const Vec3* wo, Rgb* out, std::size_t n, std::uint64_t& clamped);

}  // namespace brdfz::detail
