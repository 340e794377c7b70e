// Lobe values with their derivatives, by forward-mode autodiff (ceres::Jet) through the same
// templates that evaluate the lobes. Needs only Ceres' Jet header (and Eigen), not the solver.
#pragma once

#include <ceres/jet.h>

#include <algorithm>
#include <array>
#include <cstddef>

#include "brdfz/repr/analytic/catalogue.h"

namespace brdfz::fitting {

inline constexpr std::size_t kMaxLobeParams = [] {
    std::size_t n = 0;
    for (const LobeType& t : AllLobes::types) n = std::max(n, t.params.size());
    return n;
}();

// f per channel and its derivatives with respect to the lobe's parameters (jac[c·n + j]), by
// forward-mode autodiff through the same template that evaluates the lobe. For a lobe linear in its
// colour weights, f_c = w_c · s_c: only the shape s is differentiated by autodiff (a Jet of the
// shape parameters alone, often 1 or 2 wide), the weights' derivatives are s_c itself.
template <typename F>
void eval_with_jacobian(const Geometry<double>& g, const double* p, double value[3], double* jac) {
    constexpr int n = static_cast<int>(F::params.size());
    if constexpr (F::linear_weights) {
        constexpr int m = n - 3;
        std::fill(jac, jac + 3 * n, 0.0);
        double s[3];
        if constexpr (m == 0) {
            const double ones[3] = {1.0, 1.0, 1.0};
            F::eval(g, ones, s);
        } else {
            using J = ceres::Jet<double, m>;
            J x[n];
            for (int c = 0; c < 3; ++c) x[c] = J(1.0);
            for (int j = 0; j < m; ++j) x[3 + j] = J(p[3 + j], j);
            J out[3];
            F::eval(g, x, out);
            for (int c = 0; c < 3; ++c) {
                s[c] = out[c].a;
                for (int j = 0; j < m; ++j) jac[c * n + 3 + j] = p[c] * out[c].v[j];
            }
        }
        for (int c = 0; c < 3; ++c) {
            value[c] = p[c] * s[c];
            jac[c * n + c] = s[c];
        }
    } else {
        using J = ceres::Jet<double, n>;
        J x[n];
        for (int j = 0; j < n; ++j) x[j] = J(p[j], j);
        J out[3];
        F::eval(g, x, out);
        for (int c = 0; c < 3; ++c) {
            value[c] = out[c].a;
            for (int j = 0; j < n; ++j) jac[c * n + j] = out[c].v[j];
        }
    }
}

using JacobianEval = void (*)(const Geometry<double>&, const double*, double*, double*);
template <typename... F>
constexpr std::array<JacobianEval, sizeof...(F)> jacobian_evals(LobeList<F...>) {
    return {&eval_with_jacobian<F>...};
}
// In catalogue order, like lobe_types().
inline constexpr auto kJacobianEvals = jacobian_evals(AllLobes{});

}  // namespace brdfz::fitting
