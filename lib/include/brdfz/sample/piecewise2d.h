// A piecewise-constant 2D distribution on [0,1]², sampled by inversion: a marginal CDF over rows,
// a conditional CDF over the columns of each row. pdf() is exactly the density sample() draws from.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace brdfz {

class Piecewise2D {
public:
    Piecewise2D() = default;
    // rows × cols non-negative cell weights, row-major; ValueError if the shape is wrong or any weight
    // is negative or not finite. An all-zero grid becomes uniform (so the result is always a density).
    Piecewise2D(std::span<const float> weights, int rows, int cols);

    struct Point {
        double x, y;   // x across columns, y across rows, in [0, 1)
        double pdf;    // density on [0,1]²
        int row, col;  // the cell (x, y) lies in
    };
    Point sample(double u1, double u2) const;
    double pdf(double x, double y) const;
    // The density of cell (row, col): pdf(x, y) for any (x, y) in it, without locating it.
    double density(int row, int col) const { return density_[static_cast<std::size_t>(row) * cols_ + col]; }

    int rows() const { return rows_; }
    int cols() const { return cols_; }
    std::size_t nbytes() const {
        return (marginal_.size() + conditional_.size() + density_.size()) * sizeof(float) +
               (marginal_guide_.size() + conditional_guide_.size()) * sizeof(std::uint32_t);
    }

private:
    int rows_ = 0, cols_ = 0;
    std::vector<float> marginal_;     // rows + 1 entries, 0 … 1
    std::vector<float> conditional_;  // rows × (cols + 1), each row 0 … 1
    std::vector<float> density_;      // rows × cols cell densities
    // Where sample()'s search for u starts: per CDF of n intervals, entry j is the last interval whose
    // start is <= j/n.
    std::vector<std::uint32_t> marginal_guide_, conditional_guide_;
};

}  // namespace brdfz
