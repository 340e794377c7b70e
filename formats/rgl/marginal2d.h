// The warps of Mitsuba 3's `measured` plugin (Mitsuba's core/distr_2d.h, Marginal2D with Continuous =
// true, after Dupuy & Jakob 2018): a density given by a bilinearly interpolated table on the unit
// square, one table per slice (θi), with the CDFs that sample it. Private to the RGL reader; the
// kernels that sample, invert and evaluate the warps are in kernels.cpp.
//
// A table is a rows × cols grid of samples spanning [0,1]² (x along columns, stored fastest). Between
// slices the tables are blended entry by entry; since every slice is normalised, the blended CDFs are
// exactly the CDFs of the blended density, so sampling draws from the density for any weights.
// Every slice is normalised to integrate to 1, and the CDF tables are built as Mitsuba builds them
// (accumulated in double, stored in float), though in unit-square rather than patch units, so they
// agree with Mitsuba's to float rounding, not bit for bit.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "kernels.h"

namespace brdfz::rgl::detail {

// Each slice's tables, slice after slice: the density normalised to integrate to 1, the CDF along
// each row (`conditional`, rows × (cols − 1)) and across rows (`marginal`, rows − 1), built as Mitsuba
// builds them. ValueError (naming `what`) for a negative value or a slice that does not integrate to a
// positive finite number.
struct SliceTables {
    std::vector<float> density, conditional, marginal;
};

inline SliceTables slice_tables(const char* what, std::span<const float> values, std::size_t slices, std::size_t rows,
                                std::size_t cols) {
    for (float v : values)
        if (v < 0.0f) throw ValueError(std::string(what) + " holds a negative value");
    SliceTables t{std::vector<float>(values.begin(), values.end()), std::vector<float>(slices * rows * (cols - 1)),
                  std::vector<float>(slices * (rows - 1))};
    std::vector<double> row_total(rows);
    const double half_width = 0.5 / static_cast<double>(cols - 1);
    const double half_height = 0.5 / static_cast<double>(rows - 1);
    for (std::size_t s = 0; s < slices; ++s) {
        float* d = t.density.data() + s * rows * cols;
        float* cond = t.conditional.data() + s * rows * (cols - 1);
        float* marg = t.marginal.data() + s * (rows - 1);
        // Trapezoid rule along each row (exact for the linear interpolant), then across rows.
        for (std::size_t y = 0; y < rows; ++y) {
            double sum = 0.0;
            for (std::size_t x = 0; x + 1 < cols; ++x) {
                sum += half_width * (static_cast<double>(d[y * cols + x]) + d[y * cols + x + 1]);
                cond[y * (cols - 1) + x] = static_cast<float>(sum);
            }
            row_total[y] = sum;
        }
        double total = 0.0;
        for (std::size_t y = 0; y + 1 < rows; ++y) {
            total += half_height * (row_total[y] + row_total[y + 1]);
            marg[y] = static_cast<float>(total);
        }
        if (!(total > 0.0 && std::isfinite(total)))
            throw ValueError(std::string(what) + " slice " + std::to_string(s) + " integrates to " +
                             std::to_string(total) + ", not a positive number");
        const auto norm = static_cast<float>(1.0 / total);
        for (std::size_t k = 0; k < rows * (cols - 1); ++k) cond[k] *= norm;
        for (std::size_t k = 0; k + 1 < rows; ++k) marg[k] *= norm;
        for (std::size_t k = 0; k < rows * cols; ++k) d[k] *= norm;
    }
    return t;
}

class Marginal2D {
public:
    // ValueError (naming `what`) when a value is negative (no density), a slice does not integrate to a
    // positive finite number, or the tables in the kernels' layout would hold more values than an int
    // indexes.
    Marginal2D(const char* what, std::span<const float> values, std::size_t slices, std::size_t rows, std::size_t cols)
        : rows_(rows), cols_(cols), stride_(slice_stride(slices)) {
        if (static_cast<double>(stride_) * static_cast<double>(values.size()) / static_cast<double>(slices) >=
            static_cast<double>(std::numeric_limits<int>::max()))
            throw ValueError(std::string(what) + " is too large");
        SliceTables t = slice_tables(what, values, slices, rows, cols);
        data_ = slices_innermost(t.density.data(), slices, rows * cols);
        cond_ = slices_innermost(t.conditional.data(), slices, rows * (cols - 1));
        marg_ = slices_innermost(t.marginal.data(), slices, rows - 1);
    }

    // The tables as the kernels read them.
    WarpTables tables() const {
        return {static_cast<int>(rows_), static_cast<int>(cols_), static_cast<int>(stride_), data_.data(), cond_.data(),
                marg_.data()};
    }

private:
    std::size_t rows_, cols_, stride_;
    // In the kernels' layout (kernels.h: slices innermost).
    std::vector<float> data_;  // normalised densities, rows × cols
    std::vector<float> cond_;  // per row: CDF along x at each patch's right edge
    std::vector<float> marg_;  // CDF along y at each patch row's top edge
};

}  // namespace brdfz::rgl::detail
