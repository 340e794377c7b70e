// RglBrdf: evaluation of the Dupuy-Jakob parameterisation the way Mitsuba 3's `measured` plugin
// does it (see rgl.h for the direction mapping and the cosine).
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "marginal2d.h"

namespace brdfz::rgl {
namespace {

using detail::Point2;

// The parameterisation's unit coordinates: a square-root axis in elevation, linear in azimuth.
double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / std::numbers::pi)); }
double u_of_phi(double phi) { return (phi + std::numbers::pi) * (0.5 / std::numbers::pi); }

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
    check_grids("ndf", t.ndf, 1);
    check_grids("sigma", t.sigma, 1);
    check_grids("vndf", t.vndf, n_theta);
    check_grids("rgb", t.rgb, 3 * n_theta);
    check_finite("ndf", t.ndf.values);
    check_finite("sigma", t.sigma.values);
    check_finite("vndf", t.vndf.values);
    // Mitsuba would return NaN wherever such a value contributes; 0 keeps eval finite.
    for (float& v : t.rgb.values)
        if (!std::isfinite(v)) v = 0.0f;
    vndf_ = std::make_unique<const detail::Marginal2D>("rgl: vndf", t.vndf.values, t.vndf.slices, t.vndf.rows,
                                                       t.vndf.cols);
}

RglBrdf::~RglBrdf() = default;

std::size_t RglBrdf::nbytes() const {
    const Tensors& t = tensors_;
    const std::size_t floats =
        t.theta_i.size() + t.ndf.values.size() + t.sigma.values.size() + t.vndf.values.size() + t.rgb.values.size();
    return sizeof(float) * floats;
}

std::string RglBrdf::describe() const {
    const Tensors& t = tensors_;
    const auto grid = [](const Grids& g) { return std::to_string(g.rows) + "x" + std::to_string(g.cols); };
    return "rgl isotropic rgb " + std::to_string(t.theta_i.size()) + " theta_i x " + grid(t.rgb) + " (vndf " +
           grid(t.vndf) + ", ndf " + grid(t.ndf) + ", sigma " + grid(t.sigma) + (t.jacobian ? "" : ", no jacobian") +
           "; Mitsuba 'measured' evaluation)";
}

Rgb RglBrdf::eval_above(const Vec3& wi, const Vec3& wo) const { return eval_one(wi, wo); }

void RglBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    for (std::size_t k = 0; k < n; ++k)
        out[k] = wi[k].z > 0.0 && wo[k].z > 0.0 ? eval_one(wi[k], wo[k]) : Rgb{0.0, 0.0, 0.0};
}

Rgb RglBrdf::eval_one(const Vec3& wi, const Vec3& wo) const {
    // Brdf::eval checks only z > 0; a NaN or infinite component has no meaningful value.
    for (double v : {wi.x, wi.y, wi.z, wo.x, wo.y, wo.z})
        if (!std::isfinite(v)) return {0.0, 0.0, 0.0};
    const Tensors& t = tensors_;
    const double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    const Vec3 m = normalize(wi + wo);  // finite: both z > 0
    const double theta_m = elevation(m), phi_m = std::atan2(m.y, m.x);
    // Isotropic data is tabulated over the normal's azimuth relative to wi's, wrapped into [0, 1).
    double u_phi_m = u_of_phi(phi_m - phi_i);
    u_phi_m -= std::floor(u_phi_m);
    const Point2 u_m{u_of_theta(theta_m), u_phi_m};

    // Unit coordinates in which the RGB tables are sampled: m's position in the VNDF's CDF at θi.
    const detail::SliceWeights w = detail::slice_weights(t.theta_i, theta_i);
    const Point2 s = vndf_->invert(u_m, w);

    double scale = 1.0 / wo.z;  // the data hold f·cosθo
    if (t.jacobian) {
        const detail::SliceWeights one{};
        const double d = detail::bilinear(detail::blend(t.ndf.values.data(), 0, one), t.ndf.rows, t.ndf.cols, u_m);
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

}  // namespace brdfz::rgl
