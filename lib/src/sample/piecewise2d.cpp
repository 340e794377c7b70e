#include "brdfz/sample/piecewise2d.h"

#include <algorithm>
#include <cmath>

#include "brdfz/errors.h"

namespace brdfz {
namespace {

// Index of the CDF interval holding u: the largest i with cdf[i] <= u, among intervals of non-zero
// width, so a sample never lands in an empty cell. The guide entry of u's 1/n-wide bucket is where the
// scan starts (on average about one step): the result is that of a binary search, at a fraction of
// its cost.
int find_interval(const float* cdf, const std::uint32_t* guide, int n, double u) {
    const float x = static_cast<float>(u);
    // x·n is exact in double (24-bit x, n < 2^29), so x >= j/n and cdf[guide[j]] <= x. NaN: bucket 0.
    const int j = x > 0.0f ? std::min(static_cast<int>(static_cast<double>(x) * n), n - 1) : 0;
    int i = static_cast<int>(guide[j]);
    while (i < n - 1 && cdf[i + 1] <= x) ++i;
    while (i > 0 && cdf[i + 1] == cdf[i]) --i;
    while (i < n - 1 && cdf[i + 1] == cdf[i]) ++i;
    return i;
}

// guide[j] = the largest i in [0, n-1] with cdf[i] <= j/n (compared exactly), for j in [0, n).
void build_guide(const float* cdf, int n, std::uint32_t* guide) {
    int i = 0;
    for (int j = 0; j < n; ++j) {
        while (i < n - 1 && static_cast<double>(cdf[i + 1]) * n <= j) ++i;
        guide[j] = static_cast<std::uint32_t>(i);
    }
}

// (i + f) / n, nudged so that pdf()'s floor(v·n) finds cell i again despite rounding.
double cell_coord(int i, int n, double f) {
    double v = (i + f) / n;
    while (v * n >= i + 1.0) v = std::nextafter(v, 0.0);
    while (v * n < i) v = std::nextafter(v, 1.0);
    return v;
}

}  // namespace

Piecewise2D::Piecewise2D(std::span<const float> weights, int rows, int cols) : rows_(rows), cols_(cols) {
    if (rows < 1 || cols < 1 || weights.size() != static_cast<std::size_t>(rows) * cols)
        throw ValueError("piecewise2d: weights do not match the grid shape");
    double total = 0.0;
    std::vector<double> row_sum(rows, 0.0);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
            const float w = weights[static_cast<std::size_t>(r) * cols + c];
            if (!(w >= 0.0f) || !std::isfinite(w)) throw ValueError("piecewise2d: weights must be finite and >= 0");
            row_sum[r] += w;
        }
    for (double s : row_sum) total += s;
    const bool uniform = !(total > 0.0);

    marginal_.assign(rows + 1, 0.0f);
    conditional_.assign(static_cast<std::size_t>(rows) * (cols + 1), 0.0f);
    density_.assign(static_cast<std::size_t>(rows) * cols, 0.0f);
    double acc_rows = 0.0;
    for (int r = 0; r < rows; ++r) {
        const double rs = uniform ? cols : row_sum[r];
        acc_rows += rs;
        marginal_[r + 1] = static_cast<float>(acc_rows / (uniform ? static_cast<double>(rows) * cols : total));
        float* cdf = &conditional_[static_cast<std::size_t>(r) * (cols + 1)];
        double acc = 0.0;
        for (int c = 0; c < cols; ++c) {
            const double w = uniform ? 1.0 : weights[static_cast<std::size_t>(r) * cols + c];
            acc += w;
            cdf[c + 1] = rs > 0.0 ? static_cast<float>(acc / rs) : static_cast<float>(c + 1) / cols;
        }
        cdf[cols] = 1.0f;
    }
    marginal_[rows] = 1.0f;
    marginal_guide_.resize(rows);
    conditional_guide_.resize(static_cast<std::size_t>(rows) * cols);
    build_guide(marginal_.data(), rows, marginal_guide_.data());
    for (int r = 0; r < rows; ++r)
        build_guide(&conditional_[static_cast<std::size_t>(r) * (cols + 1)], cols,
                    &conditional_guide_[static_cast<std::size_t>(r) * cols]);
    // Densities from the stored (float) CDFs, so pdf() matches what sample() does exactly.
    for (int r = 0; r < rows; ++r) {
        const double pr = (marginal_[r + 1] - marginal_[r]) * rows;
        const float* cdf = &conditional_[static_cast<std::size_t>(r) * (cols + 1)];
        for (int c = 0; c < cols; ++c)
            density_[static_cast<std::size_t>(r) * cols + c] = static_cast<float>(pr * (cdf[c + 1] - cdf[c]) * cols);
    }
}

Piecewise2D::Point Piecewise2D::View::sample(double u1, double u2) const {
    const int r = find_interval(marginal, marginal_guide, rows, u1);
    const double w_r = marginal[r + 1] - marginal[r];
    const double fy = std::clamp((u1 - marginal[r]) / w_r, 0.0, 1.0);
    const float* cdf = conditional + static_cast<std::size_t>(r) * (cols + 1);
    const int c = find_interval(cdf, conditional_guide + static_cast<std::size_t>(r) * cols, cols, u2);
    const double fx = std::clamp((u2 - cdf[c]) / (cdf[c + 1] - cdf[c]), 0.0, 1.0);
    return {cell_coord(c, cols, fx), cell_coord(r, rows, fy), density_at(r, c), r, c};
}

double Piecewise2D::View::pdf(double x, double y) const {
    if (!(x >= 0.0 && x < 1.0 && y >= 0.0 && y < 1.0)) return 0.0;
    const int r = std::min(static_cast<int>(y * rows), rows - 1);  // the cell_coord() convention
    const int c = std::min(static_cast<int>(x * cols), cols - 1);
    return density_at(r, c);
}

}  // namespace brdfz
