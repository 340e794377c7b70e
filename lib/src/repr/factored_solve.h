// What the sample fit (factored_fit.cpp) and fit=lsq's refit through the lookup (factored_refit.cpp)
// share: each instantiates a heavy share of Eigen (the SVDs; the sparse LDLT), so they are units of
// their own that a build compiles side by side.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace brdfz::detail {

using FactorMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using FactorVec = Eigen::VectorXd;

// min ½ uᵀAu − bᵀu subject to u ≥ 0, by coordinate descent from the given u (A positive definite).
inline void nnls(const Eigen::MatrixXd& a, const FactorVec& b, FactorVec& u) {
    const Eigen::Index k = u.size();
    for (int sweep = 0; sweep < 20; ++sweep) {  // warm-started: a few sweeps per outer iteration suffice
        double change = 0.0, scale = 0.0;
        for (Eigen::Index i = 0; i < k; ++i) {
            const double next = std::max(0.0, u[i] + (b[i] - a.row(i).dot(u)) / a(i, i));
            change = std::max(change, std::fabs(next - u[i]));
            u[i] = next;
            scale = std::max(scale, next);
        }
        if (change <= 1e-9 * scale) break;
    }
}

// A factorisation in progress.
struct Solved {
    FactorMat u, v, s;  // rows × k, columns × k, channels × k
    int iterations = 0;
    bool converged = false;
    double objective = 0.0, norm = 0.0;  // Σ w (y − ŷ)², Σ w y²
};

// Each component's scale (`scale` of its U and of its V column) moved between U, V and s; the product
// is unchanged. With colour weights the scales go into s; without, U and V columns get equal scales.
template <typename Scale>
void move_column_scales(Solved& r, bool shared, Scale scale) {
    for (Eigen::Index j = 0; j < r.u.cols(); ++j) {
        const double su = scale(r.u.col(j)), sv = scale(r.v.col(j));
        if (!(su > 0.0 && sv > 0.0)) continue;
        if (shared) {
            r.u.col(j) /= su;
            r.v.col(j) /= sv;
            r.s.col(j) *= su * sv;
        } else {
            const double g = std::sqrt(su * sv);
            r.u.col(j) *= g / su;
            r.v.col(j) *= g / sv;
        }
    }
}

// Column norms balanced so that no factor's scale drifts.
inline void balance(Solved& r, bool shared) {
    move_column_scales(r, shared, [](const auto& c) { return c.norm(); });
}

// float16 storage: each component's U and V columns scaled to a largest magnitude of 1, the scale
// moved into the (float32) colour weights; for separate colour both to the geometric mean of their
// largest magnitudes. Either way far from float16's range limits, where its relative precision holds.
inline void scale_for_f16(Solved& r, bool shared) {
    move_column_scales(r, shared, [](const auto& c) { return c.cwiseAbs().maxCoeff(); });
}

}  // namespace brdfz::detail
