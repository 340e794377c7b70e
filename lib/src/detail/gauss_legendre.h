// Gauss-Legendre nodes and weights on [0, 1], by Newton iteration on P_n (Golub-Welsch is overkill
// for the small fixed orders used here).
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

namespace brdfz::detail {

struct Quadrature {
    std::vector<double> x, w;
};

inline Quadrature gauss_legendre01(int n) {
    Quadrature q{std::vector<double>(n), std::vector<double>(n)};
    for (int i = 0; i < n; ++i) {
        double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int iter = 0; iter < 100; ++iter) {
            double p0 = 1.0, p1 = 0.0;
            for (int k = 1; k <= n; ++k) {
                const double p2 = p1;
                p1 = p0;
                p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
            }
            dp = n * (z * p0 - p1) / (z * z - 1.0);
            const double dz = p0 / dp;
            z -= dz;
            if (std::fabs(dz) < 1e-15) break;
        }
        q.x[i] = 0.5 * (1.0 - z);
        q.w[i] = 1.0 / ((1.0 - z * z) * dp * dp);  // 2/((1-z²)P'²) scaled by ½ for [0, 1]
    }
    return q;
}

}  // namespace brdfz::detail
