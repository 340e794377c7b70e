// The `rgl_svd` stored form (brdfz/formats/rgl_svd.h): factorisation and expansion.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/repr/compact_table.h"

namespace brdfz::rgl {
namespace {

constexpr double kPi = std::numbers::pi;
// The θi range the weights cover: the metrics' and the renderer's (a file's slices beyond pad it).
constexpr double kMaxTheta = 80.0 * kPi / 180.0;
// Rec. 709 luminance of linear RGB, as the RGL-EPFL files' luminance tensors are of their rgb ones.
constexpr double kLuminance[3] = {0.212671, 0.715160, 0.072169};
constexpr std::size_t kMaxGridSide = 4096;

// float16 bits of v·2^-e, with e the smallest exponent >= 0 that keeps the largest |v| at most 2^15.
std::vector<std::uint16_t> scaled_half(const std::vector<float>& values, int& exponent) {
    float top = 0.0f;
    for (float v : values) top = std::max(top, std::fabs(v));
    exponent = top > 32768.0f ? static_cast<int>(std::ceil(std::log2(top / 32768.0f))) : 0;
    std::vector<std::uint16_t> out(values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        out[i] = half_from_float(std::ldexp(values[i], -exponent));
    return out;
}

// float16 bits of a matrix, row-major.
std::vector<std::uint16_t> halves(const Eigen::MatrixXd& m) {
    std::vector<std::uint16_t> out(static_cast<std::size_t>(m.size()));
    for (Eigen::Index r = 0; r < m.rows(); ++r)
        for (Eigen::Index c = 0; c < m.cols(); ++c) out[r * m.cols() + c] = half_from_float(static_cast<float>(m(r, c)));
    return out;
}

// Int8 factors: codes of a matrix, row-major, in blocks of `block` rows, each block's column rounded
// at its own step (its largest |value| / 127, itself stored as float16 bits of step·2^-exponent, the
// exponent putting the largest step in (2^14, 2^15], within the ±200 a reader takes): step (row / block,
// column).
struct Codes {
    std::vector<std::int8_t> codes;
    std::vector<std::uint16_t> steps;
    int exponent = 0;
    float step(std::size_t block, std::size_t col, std::size_t cols) const {
        return std::ldexp(half_to_float(steps[block * cols + col]), exponent);
    }
};

Codes int8_codes(const Eigen::MatrixXd& m, Eigen::Index block) {
    const Eigen::Index blocks = m.rows() / block, cols = m.cols();
    Eigen::MatrixXd top(blocks, cols);
    for (Eigen::Index b = 0; b < blocks; ++b)
        for (Eigen::Index c = 0; c < cols; ++c) top(b, c) = m.block(b * block, c, block, 1).cwiseAbs().maxCoeff() / 127.0;
    Codes out;
    const double largest = top.maxCoeff();
    out.exponent = largest > 0.0 ? std::clamp(static_cast<int>(std::ceil(std::log2(largest / 32768.0))), -200, 200) : 0;
    out.steps.resize(static_cast<std::size_t>(top.size()));
    out.codes.resize(static_cast<std::size_t>(m.size()));
    for (Eigen::Index b = 0; b < blocks; ++b)
        for (Eigen::Index c = 0; c < cols; ++c) {
            out.steps[b * cols + c] = half_from_float(static_cast<float>(std::ldexp(top(b, c), -out.exponent)));
            const double st = out.step(b, c, cols);
            for (Eigen::Index r = b * block; r < (b + 1) * block; ++r)
                out.codes[r * cols + c] = static_cast<std::int8_t>(st > 0.0 ? std::clamp(std::round(m(r, c) / st), -127.0, 127.0) : 0.0);
        }
    return out;
}

// The first row alone when every row is the same.
void one_row_if_uniform(std::vector<std::uint16_t>& bits, std::size_t rows, std::size_t cols) {
    for (std::size_t r = 1; r < rows; ++r)
        if (!std::equal(bits.begin(), bits.begin() + cols, bits.begin() + r * cols)) return;
    bits.resize(cols);
}

// The rows × cols grid of stored float16 bits (one row repeated, or every row).
std::vector<float> unscaled(const std::vector<std::uint16_t>& bits, int exponent, std::size_t rows, std::size_t cols) {
    std::vector<float> out(rows * cols);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = std::ldexp(half_to_float(bits[i % bits.size()]), exponent);
    return out;
}

// Linear interpolation of a row-major grid at unit coordinates (x along columns, y along rows).
double lerp_grid(const std::vector<float>& g, std::size_t rows, std::size_t cols, double x, double y) {
    const double fx = std::clamp(x, 0.0, 1.0) * static_cast<double>(cols - 1);
    const double fy = std::clamp(y, 0.0, 1.0) * static_cast<double>(rows - 1);
    const std::size_t x0 = std::min(static_cast<std::size_t>(fx), cols - 2), y0 = std::min(static_cast<std::size_t>(fy), rows - 2);
    const double ax = fx - static_cast<double>(x0), ay = fy - static_cast<double>(y0);
    const auto at = [&](std::size_t r, std::size_t c) { return static_cast<double>(g[r * cols + c]); };
    return (1 - ay) * ((1 - ax) * at(y0, x0) + ax * at(y0, x0 + 1)) + ay * ((1 - ax) * at(y0 + 1, x0) + ax * at(y0 + 1, x0 + 1));
}

// The slices factored: up to and including the first at or beyond kMaxTheta (which the range's
// interpolation reads up to kMaxTheta); the others are beyond what is judged or rendered.
std::size_t slices_kept(const std::vector<float>& theta_i) {
    for (std::size_t i = 0; i < theta_i.size(); ++i)
        if (theta_i[i] >= kMaxTheta - 1e-6) return i + 1;
    return theta_i.size();
}

// Row weights of the factored matrix, per (slice, rgb column): the slice's share of ∫ sinθ cos²θ / σ(θ)
// dθ over θi < kMaxTheta (its hat function in θi: what a pair's value takes of the slice), times
// D(θm)^power at the column's θm, the column's sample coordinate mapped back through the slice's
// VNDF marginal in θm.
std::vector<double> row_weights(const Tensors& t, std::size_t slices, double power) {
    const std::size_t n = t.theta_i.size(), cols = t.rgb.cols, vr = t.vndf.rows, vc = t.vndf.cols;
    std::vector<double> slice_weight(slices, 0.0);
    constexpr int kSteps = 2000;
    for (int s = 0; s <= kSteps; ++s) {
        const double theta = kMaxTheta * s / kSteps;
        const double sigma = lerp_grid(t.sigma.values, t.sigma.rows, t.sigma.cols, std::sqrt(theta / (kPi / 2)), 0.0);
        const double w = (s == 0 || s == kSteps ? 0.5 : 1.0) * std::sin(theta) * std::cos(theta) * std::cos(theta) /
                         std::max(sigma, 1e-30);
        // The hat functions of the slices around θ.
        std::size_t hi = std::upper_bound(t.theta_i.begin(), t.theta_i.end(), static_cast<float>(theta)) - t.theta_i.begin();
        if (hi == 0) {
            slice_weight[0] += w;
        } else if (hi >= n) {
            if (n - 1 < slices) slice_weight[n - 1] += w;
        } else {
            const double a = (theta - t.theta_i[hi - 1]) / (t.theta_i[hi] - t.theta_i[hi - 1]);
            if (hi - 1 < slices) slice_weight[hi - 1] += (1 - a) * w;
            if (hi < slices) slice_weight[hi] += a * w;
        }
    }
    std::vector<double> out(slices * cols);
    for (std::size_t i = 0; i < slices; ++i) {
        // The slice's marginal in θm: its VNDF averaged over φm, cumulated along u_θm.
        std::vector<double> cdf(vc, 0.0);
        for (std::size_t c = 1; c < vc; ++c) {
            double a = 0, b = 0;
            for (std::size_t r = 0; r < vr; ++r) a += t.vndf.values[(i * vr + r) * vc + c - 1], b += t.vndf.values[(i * vr + r) * vc + c];
            cdf[c] = cdf[c - 1] + 0.5 * (a + b);
        }
        for (std::size_t k = 0; k < cols; ++k) {
            const double target = cdf.back() * static_cast<double>(k) / static_cast<double>(cols - 1);
            const std::size_t c = std::min<std::size_t>(std::lower_bound(cdf.begin(), cdf.end(), target) - cdf.begin(), vc - 1);
            double u = static_cast<double>(c) / static_cast<double>(vc - 1);
            if (c > 0 && cdf[c] > cdf[c - 1])
                u -= (cdf[c] - target) / (cdf[c] - cdf[c - 1]) / static_cast<double>(vc - 1);
            const double d = std::max(lerp_grid(t.ndf.values, t.ndf.rows, t.ndf.cols, u, 0.0), 0.0);
            out[i * cols + k] = slice_weight[i] * std::pow(d, power);
        }
    }
    // A floor, so that no row is left out of the fit entirely.
    const double top = *std::max_element(out.begin(), out.end());
    for (double& w : out) w = std::max(w, 1e-3 * top);
    return out;
}

}  // namespace

Grids derived_vndf(const std::vector<float>& theta_i, const Grids& ndf, std::size_t rows, std::size_t cols) {
    // D(m)·max(0, wi·m) in the measure of the unit square (u_θm, u_φm): dθ = π·u_θ du, sinθ dφ.
    const std::size_t n = theta_i.size();
    Grids g{n, rows, cols, std::vector<float>(n * rows * cols)};
    for (std::size_t i = 0; i < n; ++i) {
        const double st = std::sin(theta_i[i]), ct = std::cos(theta_i[i]);
        for (std::size_t r = 0; r < rows; ++r) {
            const double uy = static_cast<double>(r) / static_cast<double>(rows - 1), phi = uy * 2 * kPi - kPi;
            for (std::size_t c = 0; c < cols; ++c) {
                const double ux = static_cast<double>(c) / static_cast<double>(cols - 1), theta = ux * ux * kPi / 2;
                const double cos_wm = st * std::sin(theta) * std::cos(phi) + ct * std::cos(theta);
                const double d = lerp_grid(ndf.values, ndf.rows, ndf.cols, ux, uy);
                g.values[(i * rows + r) * cols + c] =
                    static_cast<float>(std::max(d, 0.0) * std::max(cos_wm, 0.0) * std::sin(theta) * kPi * ux);
            }
        }
    }
    return g;
}

bool vndf_is_derived(const Tensors& t) {
    if (t.phi_i.size() > 1 || t.vndf.rows < 2 || t.vndf.cols < 2 || t.ndf.rows < 2 || t.ndf.cols < 2) return false;
    const Grids d = derived_vndf(t.theta_i, t.ndf, t.vndf.rows, t.vndf.cols);
    if (d.values.size() != t.vndf.values.size()) return false;
    const std::size_t plane = t.vndf.rows * t.vndf.cols;
    for (std::size_t s = 0; s < t.theta_i.size(); ++s) {
        double sum_file = 0, sum_derived = 0, worst = 0;
        for (std::size_t i = s * plane; i < (s + 1) * plane; ++i) sum_file += t.vndf.values[i], sum_derived += d.values[i];
        if (!(sum_file > 0 && sum_derived > 0)) return false;
        for (std::size_t i = s * plane; i < (s + 1) * plane; ++i)
            worst = std::max(worst, std::abs(t.vndf.values[i] / sum_file - d.values[i] / sum_derived));
        if (!(worst * static_cast<double>(plane) <= 0.5)) return false;
    }
    return true;
}

std::size_t SvdTensors::nbytes() const {
    return sizeof(float) * theta_i.size() + 2 * (ndf.size() + sigma.size() + u.size() + v.size() + u_scale.size() + v_scale.size()) +
           u8.size() + v8.size();
}

SvdTensors factor(const Tensors& t, std::size_t rank, double weight_power, SvdDtype dtype) {
    if (t.phi_i.size() > 1) throw ValueError("rgl_svd: an anisotropic RGL material (tabulated over phi_i) is not supported");
    if (!(weight_power >= 0.0 && weight_power <= 4.0)) throw ValueError("rgl_svd: weight must be in [0, 4]");
    if (!vndf_is_derived(t))
        throw ValueError("rgl_svd: the material's vndf is not the one its ndf implies (an RGL-EPFL measurement's is), "
                         "so it cannot be derived when read");
    const std::size_t slices = slices_kept(t.theta_i);
    const std::size_t rows = t.rgb.rows, cols = t.rgb.cols, m = slices * cols, n = 3 * rows;
    if (rank < 1 || rank > std::min({kMaxSvdRank, n, m}))
        throw ValueError("rgl_svd: rank must be in [1, " + std::to_string(std::min({kMaxSvdRank, n, m})) + "]");
    SvdTensors s;
    s.theta_i = t.theta_i;
    s.jacobian = t.jacobian;
    s.ndf_rows = t.ndf.rows, s.ndf_cols = t.ndf.cols, s.sigma_rows = t.sigma.rows, s.sigma_cols = t.sigma.cols;
    s.ndf = scaled_half(t.ndf.values, s.ndf_exponent);
    s.sigma = scaled_half(t.sigma.values, s.sigma_exponent);
    one_row_if_uniform(s.ndf, s.ndf_rows, s.ndf_cols);
    one_row_if_uniform(s.sigma, s.sigma_rows, s.sigma_cols);
    s.vndf_rows = t.vndf.rows, s.vndf_cols = t.vndf.cols;
    s.slices = slices, s.rows = rows, s.cols = cols, s.rank = rank;
    s.luminance = !t.luminance.values.empty();
    for (std::size_t c = 0; c < 3; ++c) {
        s.floor[c] = std::numeric_limits<float>::infinity();
        for (std::size_t i = 0; i < slices; ++i)
            for (std::size_t p = 0; p < rows * cols; ++p) s.floor[c] = std::min(s.floor[c], t.rgb.values[(i * 3 + c) * rows * cols + p]);
    }

    // The weighted matrix: row (slice, column x), column (channel, grid row y).
    const std::vector<double> w = row_weights(t, slices, weight_power);
    Eigen::MatrixXd a(m, n);
    Eigen::VectorXd root(m);
    for (std::size_t i = 0; i < slices; ++i)
        for (std::size_t x = 0; x < cols; ++x) {
            const std::size_t row = i * cols + x;
            root(row) = std::sqrt(w[row]);
            for (std::size_t c = 0; c < 3; ++c)
                for (std::size_t y = 0; y < rows; ++y)
                    a(row, c * rows + y) = root(row) * static_cast<double>(t.rgb.values[((i * 3 + c) * rows + y) * cols + x]);
        }
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto k = static_cast<Eigen::Index>(rank);
    const Eigen::MatrixXd u = root.cwiseInverse().asDiagonal() * svd.matrixU().leftCols(k) * svd.singularValues().head(k).asDiagonal();
    s.dtype = dtype;
    if (dtype == SvdDtype::F16) {
        s.u = halves(u);
        s.v = halves(svd.matrixV().leftCols(k));
        return s;
    }
    // int8: u rounded first, then v the weighted least-squares fit to u's rounded values, so that the
    // product makes up for much of u's rounding.
    Codes cu = int8_codes(u, static_cast<Eigen::Index>(cols));
    Eigen::MatrixXd rounded(m, k);
    for (Eigen::Index r = 0; r < rounded.rows(); ++r)
        for (Eigen::Index j = 0; j < k; ++j) rounded(r, j) = cu.codes[r * k + j] * static_cast<double>(cu.step(r / cols, j, rank));
    const Eigen::MatrixXd v = (root.asDiagonal() * rounded).completeOrthogonalDecomposition().solve(a).transpose();
    Codes cv = int8_codes(v, static_cast<Eigen::Index>(rows));
    s.u8 = std::move(cu.codes), s.u_scale = std::move(cu.steps), s.u_scale_exponent = cu.exponent;
    s.v8 = std::move(cv.codes), s.v_scale = std::move(cv.steps), s.v_scale_exponent = cv.exponent;
    return s;
}

Tensors expand(const SvdTensors& s) {
    const auto side = [](std::size_t n) { return n >= 2 && n <= kMaxGridSide; };
    const std::size_t n = s.theta_i.size();
    if (n < 1 || n > kMaxGridSide || !side(s.ndf_rows) || !side(s.ndf_cols) || !side(s.sigma_rows) || !side(s.sigma_cols) ||
        !side(s.vndf_rows) || !side(s.vndf_cols) || !side(s.rows) || !side(s.cols) || s.slices < 1 || s.slices > n ||
        s.rank < 1 || s.rank > kMaxSvdRank || (s.ndf.size() != s.ndf_rows * s.ndf_cols && s.ndf.size() != s.ndf_cols) ||
        (s.sigma.size() != s.sigma_rows * s.sigma_cols && s.sigma.size() != s.sigma_cols) || std::abs(s.ndf_exponent) > 200 ||
        std::abs(s.sigma_exponent) > 200 || std::abs(s.u_scale_exponent) > 200 || std::abs(s.v_scale_exponent) > 200)
        throw ValueError("rgl_svd: inconsistent shapes");
    const bool f16 = s.dtype == SvdDtype::F16;
    const std::size_t u_size = f16 ? s.u.size() : s.u8.size(), v_size = f16 ? s.v.size() : s.v8.size();
    if (u_size != s.slices * s.cols * s.rank || v_size != 3 * s.rows * s.rank ||
        (f16 ? !s.u8.empty() || !s.v8.empty() || !s.u_scale.empty() || !s.v_scale.empty()
             : !s.u.empty() || !s.v.empty() || s.u_scale.size() != s.slices * s.rank || s.v_scale.size() != 3 * s.rank))
        throw ValueError("rgl_svd: inconsistent factor shapes");
    for (float f : s.floor)
        if (std::isnan(f) || f == std::numeric_limits<float>::infinity()) throw ValueError("rgl_svd: a channel's floor is NaN or +infinity");
    for (const auto* steps : {&s.u_scale, &s.v_scale})
        for (std::uint16_t h : *steps)
            if (!std::isfinite(half_to_float(h)) || half_to_float(h) < 0.0f) throw ValueError("rgl_svd: a factor's step is not a finite value >= 0");
    Tensors t;
    t.theta_i = s.theta_i;
    t.jacobian = s.jacobian;
    t.ndf = {1, s.ndf_rows, s.ndf_cols, unscaled(s.ndf, s.ndf_exponent, s.ndf_rows, s.ndf_cols)};
    t.sigma = {1, s.sigma_rows, s.sigma_cols, unscaled(s.sigma, s.sigma_exponent, s.sigma_rows, s.sigma_cols)};

    t.vndf = derived_vndf(t.theta_i, t.ndf, s.vndf_rows, s.vndf_cols);

    const std::size_t rows = s.rows, cols = s.cols, plane = rows * cols;
    t.rgb = {3 * n, rows, cols, std::vector<float>(3 * n * plane)};
    std::vector<float> u(u_size), v(v_size);
    if (f16) {
        std::transform(s.u.begin(), s.u.end(), u.begin(), half_to_float);
        std::transform(s.v.begin(), s.v.end(), v.begin(), half_to_float);
    } else {
        const auto value = [&](std::int8_t code, std::uint16_t step, int exponent) {
            return static_cast<float>(code) * std::ldexp(half_to_float(step), exponent);
        };
        for (std::size_t i = 0; i < u.size(); ++i)
            u[i] = value(s.u8[i], s.u_scale[(i / s.rank / cols) * s.rank + i % s.rank], s.u_scale_exponent);
        for (std::size_t i = 0; i < v.size(); ++i)
            v[i] = value(s.v8[i], s.v_scale[(i / s.rank / rows) * s.rank + i % s.rank], s.v_scale_exponent);
        // Bounded so that no sum of rank products leaves float's range.
        for (const auto* f : {&u, &v})
            for (float x : *f)
                if (!(std::fabs(x) <= 1e17f)) throw ValueError("rgl_svd: a factor's value is beyond 1e17");
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t from = std::min(i, s.slices - 1);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t y = 0; y < rows; ++y)
                for (std::size_t x = 0; x < cols; ++x) {
                    const float* a = &u[(from * cols + x) * s.rank];
                    const float* b = &v[(c * rows + y) * s.rank];
                    double sum = 0;
                    for (std::size_t k = 0; k < s.rank; ++k) sum += static_cast<double>(a[k]) * b[k];
                    t.rgb.values[((i * 3 + c) * rows + y) * cols + x] = std::max(static_cast<float>(sum), s.floor[c]);
                }
    }
    if (s.luminance) {
        t.luminance = {n, rows, cols, std::vector<float>(n * plane)};
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t p = 0; p < plane; ++p) {
                double y = 0;
                for (std::size_t c = 0; c < 3; ++c) y += kLuminance[c] * t.rgb.values[(i * 3 + c) * plane + p];
                t.luminance.values[i * plane + p] = static_cast<float>(y);
            }
    }
    return t;
}

std::unique_ptr<RglBrdf> make_svd_brdf(SvdTensors stored) {
    Tensors t = expand(stored);
    return std::make_unique<RglBrdf>(std::move(t), std::make_shared<const SvdTensors>(std::move(stored)));
}

}  // namespace brdfz::rgl
