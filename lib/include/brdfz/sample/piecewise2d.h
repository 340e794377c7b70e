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

    // A distribution's tables, wherever they are stored (a Piecewise2D's own, or several distributions'
    // end to end, as HalfVectorSampler keeps its slices): the marginal CDF (rows + 1), the conditional
    // CDFs (rows × (cols + 1)), the cell densities (rows × cols), and the guide tables (rows;
    // rows × cols): entry j of a CDF of n intervals is the last interval whose start is <= j/n, where
    // sample()'s search starts.
    struct View {
        int rows, cols;
        const float *marginal, *conditional, *density;
        const std::uint32_t *marginal_guide, *conditional_guide;

        Point sample(double u1, double u2) const;
        double pdf(double x, double y) const;
        // The density of cell (row, col): pdf(x, y) for any (x, y) in it, without locating it.
        double density_at(int row, int col) const { return density[static_cast<std::size_t>(row) * cols + col]; }
        // Where several distributions of this shape are stored end to end from this one: the k-th.
        View stacked(int k) const {
            const std::size_t R = rows, C = cols;
            return {rows,
                    cols,
                    marginal + k * (R + 1),
                    conditional + k * R * (C + 1),
                    density + k * R * C,
                    marginal_guide + k * R,
                    conditional_guide + k * R * C};
        }
    };
    View view() const {
        return {rows_,          cols_, marginal_.data(), conditional_.data(), density_.data(), marginal_guide_.data(),
                conditional_guide_.data()};
    }

    Point sample(double u1, double u2) const { return view().sample(u1, u2); }
    double pdf(double x, double y) const { return view().pdf(x, y); }
    double density(int row, int col) const { return view().density_at(row, col); }

    // The stored tables (View's), for storing several distributions together.
    std::span<const float> marginal_cdf() const { return marginal_; }
    std::span<const float> conditional_cdf() const { return conditional_; }
    std::span<const float> densities() const { return density_; }
    std::span<const std::uint32_t> marginal_guide() const { return marginal_guide_; }
    std::span<const std::uint32_t> conditional_guide() const { return conditional_guide_; }

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
    // Where sample()'s search for u starts (see marginal_guide()).
    std::vector<std::uint32_t> marginal_guide_, conditional_guide_;
};

}  // namespace brdfz
