// Interpolated tables on the unit square, as Mitsuba 3's `measured` plugin uses them (Mitsuba's
// core/distr_2d.h, after Dupuy & Jakob 2018). Private to the RGL reader.
//
// A table is a rows × cols grid of samples spanning [0,1]² (x along columns, stored fastest),
// read by bilinear interpolation. A stack of such tables ("slices") tabulated at increasing
// values of a parameter (θi) is read at an in-between value by blending the two neighbouring
// slices entry by entry, before any nonlinear step, exactly as Mitsuba does.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "brdfz/errors.h"

namespace brdfz::rgl::detail {

struct Point2 {
    double x = 0, y = 0;
};

// NaN goes to 0 (fmax drops it), so every later float-to-integer conversion is defined.
inline double clamp01(double v) { return std::fmin(std::fmax(v, 0.0), 1.0); }
inline double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }

// Where a parameter value falls among the values its slices are tabulated at (increasing): the
// lower slice, the step to the upper one (0 with a single slice) and the upper slice's weight.
// Values outside the tabulated range take the end slice.
struct SliceWeights {
    std::size_t lower = 0, step = 0;
    double w_upper = 0.0;
};
inline SliceWeights slice_weights(std::span<const float> values, double x) {
    if (values.size() < 2) return {};
    // First value >= x among values[1 .. n-2], else the last: one past the interval's lower end.
    const auto it = std::lower_bound(values.begin() + 1, values.end() - 1, x, [](float v, double t) { return v < t; });
    const auto lower = static_cast<std::size_t>(it - values.begin()) - 1;
    const double p0 = values[lower], p1 = values[lower + 1];
    return {lower, 1, clamp01((x - p0) / (p1 - p0))};
}

// Two slices of a stack of equally sized tables, blended: entry i is the weighted sum of both
// slices' entries i.
struct SliceBlend {
    const float* lower;
    const float* upper;
    double w_lower, w_upper;
    double operator[](std::size_t i) const { return w_lower * lower[i] + w_upper * upper[i]; }
};
// `first` is slice 0 of the stack; consecutive slices are `stride` floats apart.
inline SliceBlend blend(const float* first, std::size_t stride, const SliceWeights& w) {
    return {first + w.lower * stride, first + (w.lower + w.step) * stride, 1.0 - w.w_upper, w.w_upper};
}

// The grid cell (patch) holding a point of [0,1]² and the point's position inside it, in [0,1]².
// Points outside the square are clamped onto it; the last row and column of samples belong to the
// patch before them.
struct Patch {
    std::size_t ix, iy;
    double fx, fy;
};
inline Patch locate(Point2 p, std::size_t rows, std::size_t cols) {
    const double sx = clamp01(p.x) * static_cast<double>(cols - 1);
    const double sy = clamp01(p.y) * static_cast<double>(rows - 1);
    const std::size_t ix = std::min(static_cast<std::size_t>(sx), cols - 2);
    const std::size_t iy = std::min(static_cast<std::size_t>(sy), rows - 2);
    return {ix, iy, sx - static_cast<double>(ix), sy - static_cast<double>(iy)};
}

// Bilinear interpolation of a rows × cols table (rows, cols >= 2) at p.
inline double bilinear(const SliceBlend& t, std::size_t rows, std::size_t cols, Point2 p) {
    const Patch q = locate(p, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    return lerp(lerp(t[i], t[i + 1], q.fx), lerp(t[i + cols], t[i + cols + 1], q.fx), q.fy);
}

// Integral over the first fraction t of a segment of length `width` along which a function goes
// linearly from v0 to v1.
inline double partial_integral(double t, double width, double v0, double v1) {
    return t * lerp(v0, v1, 0.5 * t) * width;
}

// Inverse of partial_integral on a unit-width segment: the t in [0, 1] with t·lerp(v0, v1, t/2) = s,
// for v0, v1 >= 0. Rationalised, 2s / (v0 + √(v0² + 2s(v1 − v0))), so that it has no cancellation
// and needs no special case for v0 ≈ v1 (Mitsuba switches to the constant-density solution there,
// which is off by up to 1e-4 relative, i.e. its pdf would not quite be the density it draws from).
inline double invert_partial_integral(double s, double v0, double v1) {
    const double denom = v0 + std::sqrt(std::fmax(v0 * v0 + 2.0 * s * (v1 - v0), 0.0));
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;  // 0/0 only on a segment of zero density
}

// The largest j in [0, n) with cdf(j) < u, or 0 if there is none, for a non-decreasing cdf with
// cdf(0) = 0: the cell of an inverse-CDF lookup. Cells of zero mass are never chosen (for u > 0).
template <typename Cdf>
std::size_t find_cell(std::size_t n, const Cdf& cdf, double u) {
    std::size_t first = 1, count = n - 1;  // first index with cdf >= u lies in [first, first + count]
    while (count > 0) {
        const std::size_t half = count / 2;
        if (cdf(first + half) < u) {
            first += half + 1;
            count -= half + 1;
        } else {
            count = half;
        }
    }
    return first - 1;
}

// A point of [0,1]² and the density there.
struct Warped {
    Point2 p;
    double pdf = 0.0;
};

// The 2D warp of a density given by a bilinearly interpolated table, one table per slice (Mitsuba's
// Marginal2D with Continuous = true). sample() inverts the marginal CDF of y, then the conditional
// CDF of x given y; invert() is the inverse map, i.e. the CDF transform p ↦ (F(x | y), F(y)).
// The Dupuy-Jakob parameterisation reads its RGB tables at invert(microfacet normal's (u_θ, u_φ)).
// Between slices the tables are blended entry by entry; since every slice is normalised, the blended
// CDFs are exactly the CDFs of the blended density, so sample() draws from eval() for any weights.
// Arithmetic is in double over the float tables: sample() and invert() are inverses to rounding,
// and the density they report is the one they realise.
//
// Every slice is normalised to integrate to 1, and the CDF tables are built as Mitsuba builds them
// (accumulated in double, stored in float), though in unit-square rather than patch units, so they
// agree with Mitsuba's to float rounding, not bit for bit.
class Marginal2D {
public:
    // ValueError (naming `what`) when a value is negative (no density) or a slice does not integrate
    // to a positive finite number.
    Marginal2D(const char* what, std::span<const float> data, std::size_t slices, std::size_t rows, std::size_t cols)
        : rows_(rows), cols_(cols), data_(data.begin(), data.end()) {
        for (float v : data_)
            if (v < 0.0f) throw ValueError(std::string(what) + " holds a negative value");
        cond_.resize(slices * rows * (cols - 1));
        marg_.resize(slices * (rows - 1));
        std::vector<double> row_total(rows);
        const double half_width = 0.5 / static_cast<double>(cols - 1);
        const double half_height = 0.5 / static_cast<double>(rows - 1);
        for (std::size_t s = 0; s < slices; ++s) {
            float* d = data_.data() + s * rows * cols;
            float* cond = cond_.data() + s * rows * (cols - 1);
            float* marg = marg_.data() + s * (rows - 1);
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
    }

    // A point of [0,1]² distributed with density eval(·, w), for u in [0,1]² (x and y each uniform).
    Warped sample(Point2 u, const SliceWeights& w) const {
        const std::size_t n_cond = cols_ - 1;  // conditional CDF entries per row
        const SliceBlend data = blend(data_.data(), rows_ * cols_, w);
        const SliceBlend cond = blend(cond_.data(), rows_ * n_cond, w);
        const SliceBlend marg = blend(marg_.data(), rows_ - 1, w);
        const double width = 1.0 / static_cast<double>(cols_ - 1), height = 1.0 / static_cast<double>(rows_ - 1);
        const double ux = clamp01(u.x), uy = clamp01(u.y);

        // Row of patches from the marginal CDF, then the height inside it: along a patch row the
        // marginal density (the row integral) is linear, from the patch's lower to its upper edge.
        const auto marg_at = [&](std::size_t j) { return j == 0 ? 0.0 : marg[j - 1]; };
        const std::size_t iy = find_cell(rows_ - 1, marg_at, uy);
        const std::size_t row0 = iy * n_cond, row1 = row0 + n_cond;
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        const double fy = invert_partial_integral((uy - marg_at(iy)) / height, r0, r1);

        // Column from the conditional CDF at that height (interpolated between the patch's rows),
        // then the position inside the patch, where the density is linear in x.
        const double target = ux * lerp(r0, r1, fy);
        const auto cond_at = [&](std::size_t j) {
            return j == 0 ? 0.0 : lerp(cond[row0 + j - 1], cond[row1 + j - 1], fy);
        };
        const std::size_t ix = find_cell(cols_ - 1, cond_at, target);
        const std::size_t i = iy * cols_ + ix;
        const double c0 = lerp(data[i], data[i + cols_], fy), c1 = lerp(data[i + 1], data[i + cols_ + 1], fy);
        const double fx = invert_partial_integral((target - cond_at(ix)) / width, c0, c1);
        return {{(static_cast<double>(ix) + fx) * width, (static_cast<double>(iy) + fy) * height}, lerp(c0, c1, fx)};
    }

    // The inverse of sample(): the CDF transform of p, and the density at p.
    Warped invert(Point2 p, const SliceWeights& w) const {
        const std::size_t n_cond = cols_ - 1;  // conditional CDF entries per row
        const SliceBlend data = blend(data_.data(), rows_ * cols_, w);
        const SliceBlend cond = blend(cond_.data(), rows_ * n_cond, w);
        const SliceBlend marg = blend(marg_.data(), rows_ - 1, w);
        const Patch q = locate(p, rows_, cols_);

        // Density along the patch's left and right edges, at the point's height.
        const std::size_t i = q.iy * cols_ + q.ix;
        const double c0 = lerp(data[i], data[i + cols_], q.fy), c1 = lerp(data[i + 1], data[i + cols_ + 1], q.fy);
        // Conditional CDF of x: the patches to the left, interpolated between the patch's two rows,
        // plus the part of this patch; divided by the whole row's integral at this height.
        const std::size_t row0 = q.iy * n_cond, row1 = row0 + n_cond;
        double x = partial_integral(q.fx, 1.0 / static_cast<double>(cols_ - 1), c0, c1);
        if (q.ix > 0) x += lerp(cond[row0 + q.ix - 1], cond[row1 + q.ix - 1], q.fy);
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        x /= lerp(r0, r1, q.fy);
        // Marginal CDF of y: the rows of patches below, plus the part of this one.
        double y = partial_integral(q.fy, 1.0 / static_cast<double>(rows_ - 1), r0, r1);
        if (q.iy > 0) y += marg[q.iy - 1];
        return {{x, y}, lerp(c0, c1, q.fx)};
    }

    // The density at p (integrating to 1 over [0,1]²).
    double eval(Point2 p, const SliceWeights& w) const {
        return bilinear(blend(data_.data(), rows_ * cols_, w), rows_, cols_, p);
    }

private:
    std::size_t rows_, cols_;
    std::vector<float> data_;  // normalised densities, slices × rows × cols
    std::vector<float> cond_;  // per slice and row: CDF along x at each patch's right edge
    std::vector<float> marg_;  // per slice: CDF along y at each patch row's top edge
};

}  // namespace brdfz::rgl::detail
