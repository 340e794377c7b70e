// RglBrdf's scalar reference (reference.h): written for reading, not for speed.
#include "rgl/reference.h"

#include <cmath>

#include "brdfz/coords.h"

namespace brdfz::rgl::detail {
namespace {

using namespace scalar;

// Two slices of a stack of tables blended entry by entry: slices `stride` floats apart (slice-major
// tensors), or entries `entry` floats apart with the slices innermost (the warps' tables, kernels.h).
struct Blend {
    const float* lower;
    const float* upper;
    std::size_t entry;
    double w_lower, w_upper;
    double operator[](std::size_t i) const { return w_lower * lower[i * entry] + w_upper * upper[i * entry]; }
};
Blend blend(const float* first, std::size_t stride, const SliceAxis& w) {
    return {first + w.lower * stride, first + (w.lower + w.step) * stride, 1, 1.0 - w.w, w.w};
}
Blend blend_innermost(const float* first, std::size_t entry, const SliceAxis& w) {
    return {first + w.lower, first + w.lower + w.step, entry, 1.0 - w.w, w.w};
}

// A warp of the reader's (kernels.h: slices innermost) at a pair of slices.
struct Warp {
    WarpTables t;
    WarpPoint sample(double ux, double uy, const SliceAxis& w) const {
        return warp_sample(table(t.data, w), table(t.cond, w), table(t.marg, w), rows(), cols(), ux, uy);
    }
    WarpPoint invert(double px, double py, const SliceAxis& w) const {
        return warp_invert(table(t.data, w), table(t.cond, w), table(t.marg, w), rows(), cols(), px, py);
    }
    double density(double px, double py, const SliceAxis& w) const {
        return bilinear(table(t.data, w), rows(), cols(), px, py);
    }

private:
    std::size_t rows() const { return static_cast<std::size_t>(t.rows); }
    std::size_t cols() const { return static_cast<std::size_t>(t.cols); }
    Blend table(const float* first, const SliceAxis& w) const {
        return blend_innermost(first, static_cast<std::size_t>(t.stride), w);
    }
};

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
    const SliceAxis w = slice_axis(t_.theta_i, theta_i);
    const WarpPoint s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
    double scale = 1.0 / wo.z;
    if (t_.jacobian) {
        const SliceAxis one{};
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
    const SliceAxis w = slice_axis(t_.theta_i, elevation(wo));
    const Microfacet mf = microfacet(wo, wi);
    const WarpPoint s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
    const double jacobian = solid_angle_per_unit_square(mf.ux, mf.theta, dot(wo, mf.m));
    if (!(s.pdf > 0.0 && jacobian > 0.0)) return 0.0;
    const double pdf = s.pdf * (lum_ ? Warp{lum_->tables()}.density(s.x, s.y, w) : 1.0) / jacobian;
    return std::isfinite(pdf) ? pdf : 0.0;
}

BrdfSample Reference::sample(const Vec3& wo, double u1, double u2) const {
    if (!Brdf::can_draw(wo, u1, u2) || !finite(wo)) return {};
    const SliceAxis w = slice_axis(t_.theta_i, elevation(wo));
    WarpPoint s{u2, u1, 1.0};
    if (lum_) s = Warp{lum_->tables()}.sample(s.x, s.y, w);
    const WarpPoint u_m = Warp{vndf_.tables()}.sample(s.x, s.y, w);
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
