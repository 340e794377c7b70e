// RglBrdf: evaluation and sampling of the Dupuy-Jakob parameterisation the way Mitsuba 3's
// `measured` plugin does them (see rgl.h for the direction mapping, the cosine and the sampler).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "aniso.h"
#include "marginal2d.h"

namespace brdfz::rgl {
namespace {

using detail::Point2;
using detail::Warped;

// The parameterisation's unit coordinates: a square-root axis in elevation, linear in azimuth.
double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / std::numbers::pi)); }
double u_of_phi(double phi) { return (phi + std::numbers::pi) * (0.5 / std::numbers::pi); }
double theta_of_u(double u) { return u * u * (std::numbers::pi / 2.0); }
double phi_of_u(double u) { return (2.0 * u - 1.0) * std::numbers::pi; }

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The microfacet normal between a direction w (the one the tables are conditioned on) and another,
// with its elevation and its unit coordinates; isotropic data measure m's azimuth from w's.
struct Microfacet {
    Vec3 m;
    double theta;
    Point2 u;
};
Microfacet microfacet(const Vec3& w, const Vec3& other) {
    const Vec3 m = normalize(w + other);  // finite for directions above the horizon
    const double theta = elevation(m);
    double u_phi = u_of_phi(std::atan2(m.y, m.x) - std::atan2(w.y, w.x));
    u_phi -= std::floor(u_phi);  // wrapped into [0, 1)
    return {m, theta, {u_of_theta(theta), u_phi}};
}

// dω/du_m for the direction reflected about m: dω_m/du_m = (π/2 · 2u_θ dθ)(2π dφ) sinθm = 2π²·u_θ·sinθm,
// times dω/dω_m = 4 (w·m). 0 at the pole and for back-facing m, where no density is defined.
double solid_angle_per_unit_square(double u_theta, double theta_m, double w_dot_m) {
    return std::fmax(2.0 * std::numbers::pi * std::numbers::pi * u_theta * std::sin(theta_m) * 4.0 * w_dot_m, 0.0);
}

void check_grids(const char* name, const Grids& g, std::size_t slices) {
    const std::string where = std::string("rgl: ") + name + " ";
    if (g.slices != slices)
        throw ValueError(where + "has " + std::to_string(g.slices) + " slices, expected " + std::to_string(slices));
    if (g.rows < 2 || g.cols < 2)
        throw ValueError(where + "grid " + std::to_string(g.rows) + "x" + std::to_string(g.cols) +
                         " is smaller than 2x2");
    // slices × rows × cols == size, without overflowing.
    const std::size_t n = g.values.size();
    if (n % g.slices != 0 || n / g.slices % g.rows != 0 || n / g.slices / g.rows != g.cols)
        throw ValueError(where + "holds " + std::to_string(n) + " values, not " + std::to_string(g.slices) + " x " +
                         std::to_string(g.rows) + " x " + std::to_string(g.cols));
}

void check_finite(const char* name, const std::vector<float>& v) {
    for (float x : v)
        if (!std::isfinite(x)) throw ValueError(std::string("rgl: ") + name + " holds a non-finite value");
}

}  // namespace

RglBrdf::RglBrdf(Tensors tensors) : tensors_(std::move(tensors)) {
    Tensors& t = tensors_;
    const std::size_t n_theta = t.theta_i.size();
    if (n_theta == 0) throw ValueError("rgl: theta_i is empty");
    check_finite("theta_i", t.theta_i);
    for (std::size_t k = 1; k < n_theta; ++k)
        if (!(t.theta_i[k - 1] < t.theta_i[k])) throw ValueError("rgl: theta_i is not strictly increasing");
    const std::size_t n_slices = std::max<std::size_t>(t.phi_i.size(), 1) * n_theta;
    check_grids("ndf", t.ndf, 1);
    check_grids("sigma", t.sigma, 1);
    check_grids("vndf", t.vndf, n_slices);
    check_grids("rgb", t.rgb, 3 * n_slices);
    check_finite("ndf", t.ndf.values);
    check_finite("sigma", t.sigma.values);
    check_finite("vndf", t.vndf.values);
    if (!t.luminance.values.empty()) {
        check_grids("luminance", t.luminance, n_slices);
        if (t.luminance.rows != t.rgb.rows || t.luminance.cols != t.rgb.cols)
            throw ValueError("rgl: luminance grid is not shaped like the rgb grid");
        check_finite("luminance", t.luminance.values);
    }
    // Mitsuba would return NaN wherever such a value contributes; 0 keeps eval finite.
    for (float& v : t.rgb.values)
        if (!std::isfinite(v)) v = 0.0f;
    // Nothing is measured at θi = 90° (no irradiance): a slice there pads the range for interpolation
    // (in the RGL-EPFL files a copy of the last measured slice's rgb table, at 90° less a float ulp).
    const bool padded = n_theta > 1 && t.theta_i.back() >= std::numbers::pi / 2 - 1e-6;
    measured_theta_max_ = t.theta_i[n_theta - (padded ? 2 : 1)];
    if (t.phi_i.size() > 1) {
        aniso_ = std::make_unique<const detail::Anisotropic>(t);
        return;
    }
    if (!t.luminance.values.empty()) {
        luminance_ = std::make_unique<const detail::Marginal2D>("rgl: luminance", t.luminance.values,
                                                                t.luminance.slices, t.luminance.rows,
                                                                t.luminance.cols);
    }
    vndf_ = std::make_unique<const detail::Marginal2D>("rgl: vndf", t.vndf.values, t.vndf.slices, t.vndf.rows,
                                                       t.vndf.cols);
}

RglBrdf::~RglBrdf() = default;

std::size_t RglBrdf::nbytes() const {
    const Tensors& t = tensors_;
    const std::size_t floats = t.phi_i.size() + t.theta_i.size() + t.ndf.values.size() + t.sigma.values.size() +
                               t.vndf.values.size() + t.luminance.values.size() + t.rgb.values.size();
    return sizeof(float) * floats;
}

std::string RglBrdf::describe() const {
    const Tensors& t = tensors_;
    const auto grid = [](const Grids& g) { return std::to_string(g.rows) + "x" + std::to_string(g.cols); };
    const std::string phi = aniso_ ? "anisotropic rgb " + std::to_string(t.phi_i.size()) + " phi_i x " : "isotropic rgb ";
    return "rgl " + phi + std::to_string(t.theta_i.size()) + " theta_i x " + grid(t.rgb) + " (vndf " +
           grid(t.vndf) + ", ndf " + grid(t.ndf) + ", sigma " + grid(t.sigma) + (t.jacobian ? "" : ", no jacobian") +
           (luminance_ ? "" : ", no luminance") + "; Mitsuba 'measured' evaluation and sampling)";
}

Rgb RglBrdf::eval_above(const Vec3& wi, const Vec3& wo) const { return eval_one(wi, wo); }

void RglBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    for (std::size_t k = 0; k < n; ++k)
        out[k] = wi[k].z > 0.0 && wo[k].z > 0.0 ? eval_one(wi[k], wo[k]) : Rgb{0.0, 0.0, 0.0};
}

Rgb RglBrdf::eval_one(const Vec3& wi, const Vec3& wo) const {
    if (aniso_) return aniso_->eval(wi, wo);
    // Brdf::eval checks only z > 0; a NaN or infinite component has no meaningful value.
    if (!finite(wi) || !finite(wo)) return {0.0, 0.0, 0.0};
    const Tensors& t = tensors_;
    const double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    const Microfacet mf = microfacet(wi, wo);

    // Unit coordinates in which the RGB tables are sampled: m's position in the VNDF's CDF at θi.
    const detail::SliceWeights w = detail::slice_weights(t.theta_i, theta_i);
    const Point2 s = vndf_->invert(mf.u, w).p;

    double scale = 1.0 / wo.z;  // the data hold f·cosθo
    if (t.jacobian) {
        const detail::SliceWeights one{};
        const double d = detail::bilinear(detail::blend(t.ndf.values.data(), 0, one), t.ndf.rows, t.ndf.cols, mf.u);
        const double sigma = detail::bilinear(detail::blend(t.sigma.values.data(), 0, one), t.sigma.rows,
                                              t.sigma.cols, {u_of_theta(theta_i), u_of_phi(phi_i)});
        scale *= d / (4.0 * sigma);
    }

    const std::size_t plane = t.rgb.rows * t.rgb.cols;
    Rgb f;
    for (std::size_t c = 0; c < 3; ++c) {
        const double v = detail::bilinear(detail::blend(t.rgb.values.data() + c * plane, 3 * plane, w), t.rgb.rows,
                                          t.rgb.cols, s) *
                         scale;
        // A zero sigma, an empty VNDF row or a wo.z so small that f overflows would give Inf or NaN.
        f[c] = std::isfinite(v) ? v : 0.0;
    }
    return f;
}

BrdfSample RglBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    if (aniso_) return aniso_->sample(wo, u1, u2);
    if (!finite(wo)) return {};
    // wo plays the file's incident direction (rgl.h); u in Mitsuba's order, its sample2 swapped.
    const detail::SliceWeights w = detail::slice_weights(tensors_.theta_i, elevation(wo));
    Warped s{{u2, u1}, 1.0};
    if (luminance_) s = luminance_->sample(s.p, w);
    const Warped u_m = vndf_->sample(s.p, w);

    const double theta_m = theta_of_u(u_m.p.x);
    const Vec3 m = spherical_direction(theta_m, phi_of_u(u_m.p.y) + std::atan2(wo.y, wo.x));
    const double wo_dot_m = dot(wo, m);
    const double jacobian = solid_angle_per_unit_square(u_m.p.x, theta_m, wo_dot_m);
    // Brdf::sample rejects wi below the horizon and a zero pdf (a back-facing m gives both).
    const double pdf = jacobian > 0.0 ? s.pdf * u_m.pdf / jacobian : 0.0;
    return {(2.0 * wo_dot_m) * m - wo, pdf, {}};
}

double RglBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const {
    if (aniso_) return aniso_->pdf(wo, wi);
    if (!finite(wo) || !finite(wi)) return 0.0;
    const detail::SliceWeights w = detail::slice_weights(tensors_.theta_i, elevation(wo));
    const Microfacet mf = microfacet(wo, wi);
    // The point the luminance warp must have produced, and the VNDF warp's density at u_m.
    const Warped s = vndf_->invert(mf.u, w);
    const double jacobian = solid_angle_per_unit_square(mf.u.x, mf.theta, dot(wo, mf.m));
    if (!(s.pdf > 0.0 && jacobian > 0.0)) return 0.0;
    const double pdf = s.pdf * (luminance_ ? luminance_->eval(s.p, w) : 1.0) / jacobian;
    return std::isfinite(pdf) ? pdf : 0.0;
}

}  // namespace brdfz::rgl
