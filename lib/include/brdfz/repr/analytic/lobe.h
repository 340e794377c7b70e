// The core's side of the analytic lobe families (the families, their geometry and parameter
// descriptions are brdfz::runtime's kernels, brdfz/runtime/kernels/lobes/): the batch layout the
// library's eval vectorises over, and the runtime descriptor (LobeType) through which models built from
// a string call the templates.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/lobe.h"

namespace brdfz {

// A batch of direction pairs as structure of arrays, the layout the batch kernels vectorise over.
struct GeometryBlock {
    static constexpr std::size_t kSize = 128;
    alignas(64) double ix[kSize], iy[kSize], iz[kSize], ox[kSize], oy[kSize], oz[kSize];
    alignas(64) double hx[kSize], hy[kSize], hz[kSize], d[kSize];
};

// Runtime descriptor of a family, so a model string can name it: the templates instantiated for double.
struct LobeType {
    std::string_view name;
    std::span<const ParamSpec> params;
    bool linear_weights;
    void (*eval)(const Geometry<double>& g, const double* p, double out[3]);
    // r[k], g[k], b[k] += f(pair k) for k < n: the batch kernel.
    void (*accumulate)(const GeometryBlock& geo, std::size_t n, const double* p, double* r, double* g, double* b);
};

namespace detail {

template <typename F>
void accumulate_lobe(const GeometryBlock& geo, std::size_t n, const double* p, double* __restrict r,
                     double* __restrict g, double* __restrict b) {
    // Parameters copied to locals: the compiler then knows the stores below cannot change them.
    std::array<double, F::params.size()> q;
    std::copy_n(p, q.size(), q.begin());
    for (std::size_t k = 0; k < n; ++k) {
        const Geometry<double> x{geo.ix[k], geo.iy[k], geo.iz[k], geo.ox[k], geo.oy[k],
                                 geo.oz[k], geo.hx[k], geo.hy[k], geo.hz[k], geo.d[k]};
        double out[3];
        F::eval(x, q.data(), out);
        r[k] += out[0];
        g[k] += out[1];
        b[k] += out[2];
    }
}

}  // namespace detail

template <typename F>
constexpr LobeType lobe_type() {
    return {F::name, F::params, F::linear_weights, &F::template eval<double, double>, &detail::accumulate_lobe<F>};
}

}  // namespace brdfz
