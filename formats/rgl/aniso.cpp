// Anisotropic RGL evaluation (aniso.h). Arithmetic in double over the float tables, like the isotropic
// reader: sample() and invert() are inverses to rounding and the pdf is the density sample() draws.
#include "aniso.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "brdfz/errors.h"
#include "marginal2d.h"

namespace brdfz::rgl::detail {
namespace {

using namespace scalar;

double theta_of_u(double u) { return u * u * (kPi / 2.0); }
double phi_of_u(double u) { return (2.0 * u - 1.0) * kPi; }

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

// Mitsuba's mulsign_neg: a times the opposite of b's sign (+0 counts as positive).
double mulsign_neg(double a, double b) { return std::signbit(b) ? a : -a; }

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
    return warp_sample(Blend{data_.data(), rows_ * cols_, c}, Blend{cond_.data(), rows_ * (cols_ - 1), c},
                       Blend{marg_.data(), rows_ - 1, c}, rows_, cols_, ux, uy);
}

WarpPoint SliceWarp::invert(double px, double py, const Corners& c) const {
    return warp_invert(Blend{data_.data(), rows_ * cols_, c}, Blend{cond_.data(), rows_ * (cols_ - 1), c},
                       Blend{marg_.data(), rows_ - 1, c}, rows_, cols_, px, py);
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
    const SliceAxis p = slice_axis(t_.phi_i, phi), q = slice_axis(t_.theta_i, theta);
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
