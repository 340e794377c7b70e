// The least-squares problem Ceres solves: per sample and channel one residual, grouped into chunks
// of samples per residual block so Ceres' per-block overhead stays small. Private to lib/src/fit.
#pragma once

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "brdfz/fit/fit.h"
#include "brdfz/repr/analytic/catalogue.h"
#include "jacobians.h"

namespace brdfz::fitting {

// The loss transform L of fit.h and its derivative.
struct Transform {
    FitLoss loss;
    double value(double x) const {
        switch (loss) {
            case FitLoss::Cosine: return x;
            case FitLoss::Log: return std::log1p(std::fmax(x, 0.0));
            case FitLoss::Cbrt: return std::cbrt(x);
        }
        return x;
    }
    double derivative(double x) const {
        switch (loss) {
            case FitLoss::Cosine: return 1.0;
            case FitLoss::Log: return 1.0 / (1.0 + std::fmax(x, 0.0));
            // ∛x has an infinite slope at 0; capping it keeps a zero model value from stalling the solver.
            case FitLoss::Cbrt: {
                const double r = std::fmax(std::cbrt(x), 1e-3);
                return 1.0 / (3.0 * r * r);
            }
        }
        return 1.0;
    }
};

// A robust loss ρ applied per residual, written as a residual transform ψ with ψ(r)² = ρ(r²), so the
// objective is exactly Σ ρ(r²) while every channel of every sample keeps its own residual (Ceres'
// LossFunction acts on whole residual blocks). Returns ψ(r) and ψ'(r).
struct Robust {
    RobustLoss kind;
    double scale;
    std::array<double, 2> apply(double r) const {
        const double a = std::fabs(r), b = scale;
        if (kind == RobustLoss::None || a <= 1e-8 * b) return {r, 1.0};
        double rho = 0, slope = 0;  // ρ and dρ/d|r|
        if (kind == RobustLoss::Huber) {
            if (a <= b) return {r, 1.0};
            rho = 2.0 * b * a - b * b;
            slope = 2.0 * b;
        } else {  // Cauchy
            rho = b * b * std::log1p(a * a / (b * b));
            slope = 2.0 * a / (1.0 + a * a / (b * b));
        }
        const double psi = std::sqrt(rho);
        return {std::copysign(psi, r), slope / (2.0 * psi)};
    }
};

// One term of the model as the solver sees it. Solver variables are the parameters, except
// log-scale ones (roughness, exponents), which are optimised as their logarithms.
struct Term {
    int type;  // index into AllLobes
    std::size_t offset, size;
};

struct Samples {
    std::vector<Geometry<double>> geometry;
    std::vector<double> cos_i;
    std::vector<std::array<double, 3>> target;  // L(f·cosθi) of the data
};

struct Setup {
    std::vector<Term> terms;
    std::vector<bool> log_scale;  // per parameter of the model
    Transform transform;
    Robust robust;

    // Natural parameter values from solver variables of term t.
    void natural(const Term& t, const double* u, double* p) const {
        for (std::size_t j = 0; j < t.size; ++j) p[j] = log_scale[t.offset + j] ? std::exp(u[j]) : u[j];
    }
};

// Residuals of samples [begin, end): 3 per sample, channel-major within a sample. One parameter
// block per term.
class ChunkCost final : public ceres::CostFunction {
public:
    static constexpr std::size_t kChunk = 128;

    ChunkCost(const Setup& setup, const Samples& samples, std::size_t begin, std::size_t end)
        : setup_(setup), samples_(samples), begin_(begin), end_(end) {
        set_num_residuals(static_cast<int>(3 * (end - begin)));
        for (const Term& t : setup.terms) mutable_parameter_block_sizes()->push_back(static_cast<int>(t.size));
    }

    bool Evaluate(double const* const* u, double* residuals, double** jacobians) const override {
        double p[Model::kMaxTerms][kMaxLobeParams];
        for (std::size_t t = 0; t < setup_.terms.size(); ++t) setup_.natural(setup_.terms[t], u[t], p[t]);
        double jac[Model::kMaxTerms][3 * kMaxLobeParams];
        for (std::size_t k = begin_; k < end_; ++k) {
            const Geometry<double>& g = samples_.geometry[k];
            double f[3] = {0.0, 0.0, 0.0};
            for (std::size_t t = 0; t < setup_.terms.size(); ++t) {
                const Term& term = setup_.terms[t];
                double v[3];
                if (jacobians)
                    kJacobianEvals[term.type](g, p[t], v, jac[t]);
                else
                    lobe_types()[term.type].eval(g, p[t], v);
                for (int c = 0; c < 3; ++c) f[c] += v[c];
            }
            const double ci = samples_.cos_i[k];
            for (int c = 0; c < 3; ++c) {
                const std::size_t row = 3 * (k - begin_) + c;
                const double x = f[c] * ci;
                const auto [psi, dpsi] = setup_.robust.apply(setup_.transform.value(x) - samples_.target[k][c]);
                if (!std::isfinite(psi)) return false;  // Ceres then shortens the step
                residuals[row] = psi;
                if (!jacobians) continue;
                const double chain = dpsi * setup_.transform.derivative(x) * ci;
                for (std::size_t t = 0; t < setup_.terms.size(); ++t) {
                    if (!jacobians[t]) continue;
                    const Term& term = setup_.terms[t];
                    for (std::size_t j = 0; j < term.size; ++j) {
                        // d/du = d/dp · p for a parameter optimised as u = ln p.
                        const double dp = setup_.log_scale[term.offset + j] ? p[t][j] : 1.0;
                        jacobians[t][row * term.size + j] = chain * jac[t][c * term.size + j] * dp;
                    }
                }
            }
        }
        return true;
    }

private:
    const Setup& setup_;
    const Samples& samples_;
    std::size_t begin_, end_;
};

}  // namespace brdfz::fitting
