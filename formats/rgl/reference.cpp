// RglBrdf's scalar reference (reference.h): written for reading, not for speed.
#include "rgl/reference.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "brdfz/coords.h"

namespace brdfz::rgl::detail {
namespace {

constexpr double kPi = std::numbers::pi;

double clamp01(double v) { return std::fmin(std::fmax(v, 0.0), 1.0); }
double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }

struct Weights {
    std::size_t lower = 0, step = 0;
    double w_upper = 0.0;
};
Weights slice_weights(std::span<const float> values, double x) {
    if (values.size() < 2) return {};
    const auto it = std::lower_bound(values.begin() + 1, values.end() - 1, x, [](float v, double t) { return v < t; });
    const auto lower = static_cast<std::size_t>(it - values.begin()) - 1;
    const double p0 = values[lower], p1 = values[lower + 1];
    return {lower, 1, clamp01((x - p0) / (p1 - p0))};
}

// Two slices of a stack of tables blended entry by entry: slices `stride` floats apart (slice-major
// tensors), or entries `entry` floats apart with the slices innermost (the warps' tables, kernels.h).
struct Blend {
    const float* lower;
    const float* upper;
    std::size_t entry;
    double w_lower, w_upper;
    double operator[](std::size_t i) const { return w_lower * lower[i * entry] + w_upper * upper[i * entry]; }
};
Blend blend(const float* first, std::size_t stride, const Weights& w) {
    return {first + w.lower * stride, first + (w.lower + w.step) * stride, 1, 1.0 - w.w_upper, w.w_upper};
}
Blend blend_innermost(const float* first, std::size_t entry, const Weights& w) {
    return {first + w.lower, first + w.lower + w.step, entry, 1.0 - w.w_upper, w.w_upper};
}

struct Patch {
    std::size_t ix, iy;
    double fx, fy;
};
Patch locate(double x, double y, std::size_t rows, std::size_t cols) {
    const double sx = clamp01(x) * static_cast<double>(cols - 1), sy = clamp01(y) * static_cast<double>(rows - 1);
    const std::size_t ix = std::min(static_cast<std::size_t>(sx), cols - 2);
    const std::size_t iy = std::min(static_cast<std::size_t>(sy), rows - 2);
    return {ix, iy, sx - static_cast<double>(ix), sy - static_cast<double>(iy)};
}
double bilinear(const Blend& t, std::size_t rows, std::size_t cols, double x, double y) {
    const Patch q = locate(x, y, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    return lerp(lerp(t[i], t[i + 1], q.fx), lerp(t[i + cols], t[i + cols + 1], q.fx), q.fy);
}
double partial_integral(double t, double width, double v0, double v1) { return t * lerp(v0, v1, 0.5 * t) * width; }
double invert_partial_integral(double s, double v0, double v1) {
    const double denom = v0 + std::sqrt(std::fmax(v0 * v0 + 2.0 * s * (v1 - v0), 0.0));
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;
}
template <typename Cdf>
std::size_t find_cell(std::size_t n, const Cdf& cdf, double u) {
    std::size_t first = 1, count = n - 1;
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

struct Warped {
    double x, y, pdf;
};

struct Warp {
    WarpTables t;
    std::size_t R() const { return static_cast<std::size_t>(t.rows); }
    std::size_t C() const { return static_cast<std::size_t>(t.cols); }

    Warped sample(double ux, double uy, const Weights& w) const {
        const std::size_t rows = R(), cols = C(), n_cond = cols - 1;
        const std::size_t S = static_cast<std::size_t>(t.stride);
        const Blend data = blend_innermost(t.data, S, w), cond = blend_innermost(t.cond, S, w),
                    marg = blend_innermost(t.marg, S, w);
        const double width = 1.0 / static_cast<double>(cols - 1), height = 1.0 / static_cast<double>(rows - 1);
        ux = clamp01(ux), uy = clamp01(uy);
        const auto marg_at = [&](std::size_t j) { return j == 0 ? 0.0 : marg[j - 1]; };
        const std::size_t iy = find_cell(rows - 1, marg_at, uy);
        const std::size_t row0 = iy * n_cond, row1 = row0 + n_cond;
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        const double fy = invert_partial_integral((uy - marg_at(iy)) / height, r0, r1);
        const double target = ux * lerp(r0, r1, fy);
        const auto cond_at = [&](std::size_t j) {
            return j == 0 ? 0.0 : lerp(cond[row0 + j - 1], cond[row1 + j - 1], fy);
        };
        const std::size_t ix = find_cell(cols - 1, cond_at, target);
        const std::size_t i = iy * cols + ix;
        const double c0 = lerp(data[i], data[i + cols], fy), c1 = lerp(data[i + 1], data[i + cols + 1], fy);
        const double fx = invert_partial_integral((target - cond_at(ix)) / width, c0, c1);
        return {(static_cast<double>(ix) + fx) * width, (static_cast<double>(iy) + fy) * height, lerp(c0, c1, fx)};
    }

    Warped invert(double px, double py, const Weights& w) const {
        const std::size_t rows = R(), cols = C(), n_cond = cols - 1;
        const std::size_t S = static_cast<std::size_t>(t.stride);
        const Blend data = blend_innermost(t.data, S, w), cond = blend_innermost(t.cond, S, w),
                    marg = blend_innermost(t.marg, S, w);
        const Patch q = locate(px, py, rows, cols);
        const std::size_t i = q.iy * cols + q.ix;
        const double c0 = lerp(data[i], data[i + cols], q.fy), c1 = lerp(data[i + 1], data[i + cols + 1], q.fy);
        const std::size_t row0 = q.iy * n_cond, row1 = row0 + n_cond;
        double x = partial_integral(q.fx, 1.0 / static_cast<double>(cols - 1), c0, c1);
        if (q.ix > 0) x += lerp(cond[row0 + q.ix - 1], cond[row1 + q.ix - 1], q.fy);
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        x /= lerp(r0, r1, q.fy);
        double y = partial_integral(q.fy, 1.0 / static_cast<double>(rows - 1), r0, r1);
        if (q.iy > 0) y += marg[q.iy - 1];
        return {x, y, lerp(c0, c1, q.fx)};
    }

    double density(double px, double py, const Weights& w) const {
        return bilinear(blend_innermost(t.data, static_cast<std::size_t>(t.stride), w), R(), C(), px, py);
    }
};

double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / kPi)); }
double u_of_phi(double phi) { return (phi + kPi) * (0.5 / kPi); }
bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

struct Microfacet {
    Vec3 m;
    double theta, ux, uy;
};
Microfacet microfacet(const Vec3& w, const Vec3& other) {
    const Vec3 m = normalize(w + other);
    const double theta = elevation(m);
    double u_phi = u_of_phi(std::atan2(m.y, m.x) - std::atan2(w.y, w.x));
    u_phi -= std::floor(u_phi);
    return {m, theta, u_of_theta(theta), u_phi};
}
double solid_angle_per_unit_square(double u_theta, double theta_m, double w_dot_m) {
    return std::fmax(2.0 * kPi * kPi * u_theta * std::sin(theta_m) * 4.0 * w_dot_m, 0.0);
}

}  // namespace

Reference::Reference(const RglBrdf& b)
    : t_(b.tensors()),
      vndf_("vndf", t_.vndf.values, t_.vndf.slices, t_.vndf.rows, t_.vndf.cols),
      lum_(t_.luminance.values.empty()
               ? nullptr
               : std::make_unique<Marginal2D>("luminance", t_.luminance.values, t_.luminance.slices,
                                              t_.luminance.rows, t_.luminance.cols)) {}

Rgb Reference::eval(const Vec3& wi, const Vec3& wo) const {
    if (!(wi.z > 0 && wo.z > 0) || !finite(wi) || !finite(wo)) return {0, 0, 0};
    const double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    const Microfacet mf = microfacet(wi, wo);
    const Weights w = slice_weights(t_.theta_i, theta_i);
    const Warped s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
    double scale = 1.0 / wo.z;
    if (t_.jacobian) {
        const Weights one{};
        const double d = bilinear(blend(t_.ndf.values.data(), 0, one), t_.ndf.rows, t_.ndf.cols, mf.ux, mf.uy);
        const double sigma = bilinear(blend(t_.sigma.values.data(), 0, one), t_.sigma.rows, t_.sigma.cols,
                                      u_of_theta(theta_i), u_of_phi(phi_i));
        scale *= d / (4.0 * sigma);
    }
    const std::size_t plane = t_.rgb.rows * t_.rgb.cols;
    Rgb f;
    for (std::size_t c = 0; c < 3; ++c) {
        const double v = bilinear(blend(t_.rgb.values.data() + c * plane, 3 * plane, w), t_.rgb.rows, t_.rgb.cols,
                                  s.x, s.y) *
                         scale;
        f[c] = std::isfinite(v) ? v : 0.0;
    }
    return f;
}

double Reference::pdf(const Vec3& wo, const Vec3& wi) const {
    if (!(wo.z > 0 && wi.z > 0) || !finite(wo) || !finite(wi)) return 0;
    const Weights w = slice_weights(t_.theta_i, elevation(wo));
    const Microfacet mf = microfacet(wo, wi);
    const Warped s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
    const double jacobian = solid_angle_per_unit_square(mf.ux, mf.theta, dot(wo, mf.m));
    if (!(s.pdf > 0.0 && jacobian > 0.0)) return 0.0;
    const double pdf = s.pdf * (lum_ ? Warp{lum_->tables()}.density(s.x, s.y, w) : 1.0) / jacobian;
    return std::isfinite(pdf) ? pdf : 0.0;
}

BrdfSample Reference::sample(const Vec3& wo, double u1, double u2) const {
    if (!Brdf::can_draw(wo, u1, u2) || !finite(wo)) return {};
    const Weights w = slice_weights(t_.theta_i, elevation(wo));
    Warped s{u2, u1, 1.0};
    if (lum_) s = Warp{lum_->tables()}.sample(s.x, s.y, w);
    const Warped u_m = Warp{vndf_.tables()}.sample(s.x, s.y, w);
    const double theta_m = u_m.x * u_m.x * (kPi / 2.0);
    const Vec3 m = spherical_direction(theta_m, (2.0 * u_m.y - 1.0) * kPi + std::atan2(wo.y, wo.x));
    const double wo_dot_m = dot(wo, m);
    const double jacobian = solid_angle_per_unit_square(u_m.x, theta_m, wo_dot_m);
    const double pdf = jacobian > 0.0 ? s.pdf * u_m.pdf / jacobian : 0.0;
    BrdfSample out{(2.0 * wo_dot_m) * m - wo, pdf, {}};
    if (!Brdf::usable(out)) return {};
    const Rgb f = eval(out.wi, wo);
    for (int c = 0; c < 3; ++c) out.weight[c] = f[c] * out.wi.z / out.pdf;
    return out;
}

}  // namespace brdfz::rgl::detail
