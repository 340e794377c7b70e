// Anisotropic RGL evaluation (aniso.h). Arithmetic in double over the float tables, like the isotropic
// reader: sample() and invert() are inverses to rounding and the pdf is the density sample() draws.
#include "aniso.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "brdfz/errors.h"
#include "marginal2d.h"

namespace brdfz::rgl::detail {
namespace {

constexpr double kPi = std::numbers::pi;

double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / kPi)); }
double u_of_phi(double phi) { return (phi + kPi) * (0.5 / kPi); }
double theta_of_u(double u) { return u * u * (kPi / 2.0); }
double phi_of_u(double u) { return (2.0 * u - 1.0) * kPi; }
double clamp01(double v) { return std::fmin(std::fmax(v, 0.0), 1.0); }  // NaN goes to 0
double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }
bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The corner slices' entries i of a stack of tables `stride` floats apart, blended.
struct Blend {
    const float* base;
    std::size_t stride;
    const Corners& c;
    double operator[](std::size_t i) const {
        double v = 0.0;
        for (int k = 0; k < 4; ++k) v += c.weight[k] * base[c.slice[k] * stride + i];
        return v;
    }
};

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

template <typename Table>
double bilinear(const Table& t, std::size_t rows, std::size_t cols, double x, double y) {
    const Patch q = locate(x, y, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    return lerp(lerp(t[i], t[i + 1], q.fx), lerp(t[i + cols], t[i + cols + 1], q.fx), q.fy);
}

double partial_integral(double t, double width, double v0, double v1) { return t * lerp(v0, v1, 0.5 * t) * width; }
// The t in [0, 1] with t·lerp(v0, v1, t/2) = s, rationalised (no cancellation, no special case).
double invert_partial_integral(double s, double v0, double v1) {
    const double denom = v0 + std::sqrt(std::fmax(v0 * v0 + 2.0 * s * (v1 - v0), 0.0));
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;
}
// The largest j in [0, n) with cdf(j) < u, or 0 (cdf non-decreasing, cdf(0) = 0).
template <typename Cdf>
std::size_t find_cell(std::size_t n, const Cdf& cdf, double u) {
    std::size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const std::size_t mid = (lo + hi + 1) / 2;
        if (cdf(mid) < u) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

// Where x falls among increasing values (Mitsuba's interval search, clamped): lower index, step to
// the upper one (0 for a single value) and the upper one's weight.
struct Axis {
    std::size_t lower = 0, step = 0;
    double w = 0.0;
};
Axis axis(const std::vector<float>& v, double x) {
    if (v.size() < 2) return {};
    const auto it = std::lower_bound(v.begin() + 1, v.end() - 1, x, [](float a, double b) { return a < b; });
    const auto lower = static_cast<std::size_t>(it - v.begin()) - 1;
    return {lower, 1, clamp01((x - v[lower]) / (static_cast<double>(v[lower + 1]) - v[lower]))};
}

// Mitsuba's mulsign_neg: a times the opposite of b's sign (+0 counts as positive).
double mulsign_neg(double a, double b) { return std::signbit(b) ? a : -a; }

// dω/du_m for the direction reflected about m (see brdf.cpp); 0 for back-facing m.
double solid_angle_per_unit_square(double u_theta, double theta_m, double w_dot_m) {
    return std::fmax(2.0 * kPi * kPi * u_theta * std::sin(theta_m) * 4.0 * w_dot_m, 0.0);
}

}  // namespace

SliceWarp::SliceWarp(const char* what, const std::vector<float>& data, std::size_t slices, std::size_t rows,
                     std::size_t cols)
    : rows_(rows), cols_(cols) {
    SliceTables t = slice_tables(what, data, slices, rows, cols);
    data_ = std::move(t.density);
    cond_ = std::move(t.conditional);
    marg_ = std::move(t.marginal);
}

WarpPoint SliceWarp::sample(double ux, double uy, const Corners& c) const {
    const std::size_t n_cond = cols_ - 1;
    const Blend data{data_.data(), rows_ * cols_, c}, cond{cond_.data(), rows_ * n_cond, c},
        marg{marg_.data(), rows_ - 1, c};
    const double width = 1.0 / static_cast<double>(cols_ - 1), height = 1.0 / static_cast<double>(rows_ - 1);
    ux = clamp01(ux);
    uy = clamp01(uy);
    const auto marg_at = [&](std::size_t j) { return j == 0 ? 0.0 : marg[j - 1]; };
    const std::size_t iy = find_cell(rows_ - 1, marg_at, uy);
    const std::size_t row0 = iy * n_cond, row1 = row0 + n_cond;
    const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
    const double fy = invert_partial_integral((uy - marg_at(iy)) / height, r0, r1);
    const double target = ux * lerp(r0, r1, fy);
    const auto cond_at = [&](std::size_t j) { return j == 0 ? 0.0 : lerp(cond[row0 + j - 1], cond[row1 + j - 1], fy); };
    const std::size_t ix = find_cell(cols_ - 1, cond_at, target);
    const std::size_t i = iy * cols_ + ix;
    const double c0 = lerp(data[i], data[i + cols_], fy), c1 = lerp(data[i + 1], data[i + cols_ + 1], fy);
    const double fx = invert_partial_integral((target - cond_at(ix)) / width, c0, c1);
    return {(static_cast<double>(ix) + fx) * width, (static_cast<double>(iy) + fy) * height, lerp(c0, c1, fx)};
}

WarpPoint SliceWarp::invert(double px, double py, const Corners& c) const {
    const std::size_t n_cond = cols_ - 1;
    const Blend data{data_.data(), rows_ * cols_, c}, cond{cond_.data(), rows_ * n_cond, c},
        marg{marg_.data(), rows_ - 1, c};
    const Patch q = locate(px, py, rows_, cols_);
    const std::size_t i = q.iy * cols_ + q.ix;
    const double c0 = lerp(data[i], data[i + cols_], q.fy), c1 = lerp(data[i + 1], data[i + cols_ + 1], q.fy);
    const std::size_t row0 = q.iy * n_cond, row1 = row0 + n_cond;
    double x = partial_integral(q.fx, 1.0 / static_cast<double>(cols_ - 1), c0, c1);
    if (q.ix > 0) x += lerp(cond[row0 + q.ix - 1], cond[row1 + q.ix - 1], q.fy);
    const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
    x /= lerp(r0, r1, q.fy);
    double y = partial_integral(q.fy, 1.0 / static_cast<double>(rows_ - 1), r0, r1);
    if (q.iy > 0) y += marg[q.iy - 1];
    return {x, y, lerp(c0, c1, q.fx)};
}

double SliceWarp::eval(double x, double y, const Corners& c) const {
    return bilinear(Blend{data_.data(), rows_ * cols_, c}, rows_, cols_, x, y);
}

Anisotropic::Anisotropic(const Tensors& t)
    : t_(t),
      relative_azimuth_(t.phi_i.size() <= 2),
      reduction_(1),
      vndf_("rgl: vndf", t.vndf.values, t.vndf.slices, t.vndf.rows, t.vndf.cols) {
    const std::vector<float>& phi = t.phi_i;
    if (phi.size() < 2) throw ValueError("rgl: an anisotropic table needs at least 2 phi_i values");
    for (float v : phi)
        if (!std::isfinite(v)) throw ValueError("rgl: phi_i holds a non-finite value");
    for (std::size_t k = 1; k < phi.size(); ++k)
        if (!(phi[k - 1] < phi[k])) throw ValueError("rgl: phi_i is not strictly increasing");
    if (!relative_azimuth_) {
        const double k = std::rint(2.0 * kPi / (static_cast<double>(phi.back()) - phi.front()));
        reduction_ = k == 2.0 || k == 4.0 ? static_cast<int>(k) : 1;
    }
    if (!t.luminance.values.empty())
        luminance_.emplace("rgl: luminance", t.luminance.values, t.luminance.slices, t.luminance.rows,
                           t.luminance.cols);
}

Corners Anisotropic::corners(double phi, double theta) const {
    const Axis p = axis(t_.phi_i, phi), q = axis(t_.theta_i, theta);
    const std::size_t n_theta = t_.theta_i.size();
    Corners c;
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
            c.slice[2 * a + b] = (p.lower + a * p.step) * n_theta + q.lower + b * q.step;
            c.weight[2 * a + b] = (a ? p.w : 1.0 - p.w) * (b ? q.w : 1.0 - q.w);
        }
    return c;
}

namespace {

// Both directions mapped into the stored copy, by the signs of the first one's x and y.
struct Folded {
    Vec3 a, b;
    double sx = -1.0, sy = -1.0;  // mulsign_neg by -1 changes nothing
};
Folded fold(const Vec3& a, const Vec3& b, int reduction) {
    Folded f{a, b};
    if (reduction >= 2) {
        f.sy = a.y;
        f.sx = reduction == 4 ? a.x : a.y;
        for (Vec3* v : {&f.a, &f.b}) {
            v->x = mulsign_neg(v->x, f.sx);
            v->y = mulsign_neg(v->y, f.sy);
        }
    }
    return f;
}

}  // namespace

Rgb Anisotropic::eval(const Vec3& wi_, const Vec3& wo_) const {
    if (!finite(wi_) || !finite(wo_)) return {0.0, 0.0, 0.0};
    const Folded f = fold(wi_, wo_, reduction_);
    const Vec3 &wi = f.a, &wo = f.b;
    const double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    const Vec3 m = normalize(wi + wo);
    const double theta_m = elevation(m);
    double u_phi = u_of_phi(std::atan2(m.y, m.x) - (relative_azimuth_ ? phi_i : 0.0));
    u_phi -= std::floor(u_phi);
    const double u_theta = u_of_theta(theta_m);
    const Corners c = corners(phi_i, theta_i);
    const WarpPoint s = vndf_.invert(u_theta, u_phi, c);

    double scale = 1.0 / wo.z;  // the data hold f·cosθo
    if (t_.jacobian) {
        const double d = bilinear(t_.ndf.values, t_.ndf.rows, t_.ndf.cols, u_theta, u_phi);
        const double sigma = bilinear(t_.sigma.values, t_.sigma.rows, t_.sigma.cols, u_of_theta(theta_i), u_of_phi(phi_i));
        scale *= d / (4.0 * sigma);
    }
    const std::size_t plane = t_.rgb.rows * t_.rgb.cols;
    Rgb out;
    for (std::size_t ch = 0; ch < 3; ++ch) {
        const double v =
            bilinear(Blend{t_.rgb.values.data() + ch * plane, 3 * plane, c}, t_.rgb.rows, t_.rgb.cols, s.x, s.y) * scale;
        out[ch] = std::isfinite(v) ? v : 0.0;
    }
    return out;
}

BrdfSample Anisotropic::sample(const Vec3& wo_, double u1, double u2) const {
    if (!finite(wo_)) return {};
    const Folded f = fold(wo_, wo_, reduction_);
    const Vec3& wo = f.a;
    const double phi_o = std::atan2(wo.y, wo.x);
    const Corners c = corners(phi_o, elevation(wo));
    WarpPoint s{u2, u1, 1.0};
    if (luminance_) s = luminance_->sample(s.x, s.y, c);
    const WarpPoint u_m = vndf_.sample(s.x, s.y, c);
    const double theta_m = theta_of_u(u_m.x);
    const Vec3 m = spherical_direction(theta_m, phi_of_u(u_m.y) + (relative_azimuth_ ? phi_o : 0.0));
    const double wo_dot_m = dot(wo, m);
    const double jacobian = solid_angle_per_unit_square(u_m.x, theta_m, wo_dot_m);
    Vec3 wi = (2.0 * wo_dot_m) * m - wo;
    wi.x = mulsign_neg(wi.x, f.sx);
    wi.y = mulsign_neg(wi.y, f.sy);
    return {wi, jacobian > 0.0 ? s.pdf * u_m.pdf / jacobian : 0.0, {}};
}

double Anisotropic::pdf(const Vec3& wo_, const Vec3& wi_) const {
    if (!finite(wo_) || !finite(wi_)) return 0.0;
    const Folded f = fold(wo_, wi_, reduction_);
    const Vec3 &wo = f.a, &wi = f.b;
    const double phi_o = std::atan2(wo.y, wo.x);
    const Vec3 m = normalize(wo + wi);
    const double theta_m = elevation(m);
    double u_phi = u_of_phi(std::atan2(m.y, m.x) - (relative_azimuth_ ? phi_o : 0.0));
    u_phi -= std::floor(u_phi);
    const double u_theta = u_of_theta(theta_m);
    const Corners c = corners(phi_o, elevation(wo));
    const WarpPoint s = vndf_.invert(u_theta, u_phi, c);
    const double jacobian = solid_angle_per_unit_square(u_theta, theta_m, dot(wo, m));
    if (!(s.pdf > 0.0 && jacobian > 0.0)) return 0.0;
    const double pdf = s.pdf * (luminance_ ? luminance_->eval(s.x, s.y, c) : 1.0) / jacobian;
    return std::isfinite(pdf) ? pdf : 0.0;
}

}  // namespace brdfz::rgl::detail
