// RglBrdf: evaluation and sampling of the Dupuy-Jakob parameterisation the way Mitsuba 3's
// `measured` plugin does them (see rgl.h for the direction mapping, the cosine and the sampler), through
// the batch kernels of kernels.cpp, one call at a time included.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/simd.h"
#include "aniso.h"
#include "kernels.h"
#include "marginal2d.h"

namespace brdfz::rgl {
namespace {

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
    if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw ValueError(where + "holds more than 2^31 values");  // the kernels index with ints
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
    if (t.phi_i.size() > 1) {  // tabulated over φi too: detail::Anisotropic does all the work, one pair at a time
        aniso_ = std::make_unique<const detail::Anisotropic>(t);
        return;
    }
    if (!t.luminance.values.empty()) {
        // Real files hold slightly negative luminance (noise; Mitsuba renders them): it is only the
        // sampler's first warp, so it is sampled as max(v, 0), and not at all when a slice has no mass.
        std::vector<float> density(t.luminance.values.size());
        std::transform(t.luminance.values.begin(), t.luminance.values.end(), density.begin(),
                       [](float v) { return std::fmax(v, 0.0f); });
        const std::size_t plane = t.luminance.rows * t.luminance.cols;
        bool every_slice = true;
        for (std::size_t k = 0; k < t.luminance.slices; ++k)
            every_slice = every_slice && std::any_of(density.begin() + k * plane, density.begin() + (k + 1) * plane,
                                                     [](float v) { return v > 0.0f; });
        if (every_slice)
            luminance_ = std::make_unique<const detail::Marginal2D>("rgl: luminance", density, t.luminance.slices,
                                                                    t.luminance.rows, t.luminance.cols);
    }
    vndf_ = std::make_unique<const detail::Marginal2D>("rgl: vndf", t.vndf.values, t.vndf.slices, t.vndf.rows,
                                                       t.vndf.cols);
    // Each point's channels, slices innermost (kernels.h): the planes (3s + c) of the tensor as 3N
    // entries of n_theta slices.
    const std::size_t plane = t.rgb.rows * t.rgb.cols;
    if (static_cast<double>(3 * plane) * static_cast<double>(detail::slice_stride(n_theta)) >=
        static_cast<double>(std::numeric_limits<int>::max()))
        throw ValueError("rgl: rgb is too large");  // the kernels index with ints
    std::vector<float> by_slice(n_theta * 3 * plane);
    for (std::size_t s = 0; s < n_theta; ++s)
        for (std::size_t i = 0; i < plane; ++i)
            for (std::size_t c = 0; c < 3; ++c) by_slice[(s * plane + i) * 3 + c] = t.rgb.values[(s * 3 + c) * plane + i];
    rgb_ = detail::slices_innermost(by_slice.data(), n_theta, 3 * plane);
}

RglBrdf::RglBrdf(Tensors tensors, std::shared_ptr<const SvdTensors> stored) : RglBrdf(std::move(tensors)) {
    if (aniso_) throw ValueError("rgl_svd: isotropic materials only");
    svd_ = std::move(stored);
}

RglBrdf::~RglBrdf() = default;

std::size_t RglBrdf::nbytes() const {
    if (svd_) return svd_->nbytes();
    const Tensors& t = tensors_;
    const std::size_t floats = t.phi_i.size() + t.theta_i.size() + t.ndf.values.size() + t.sigma.values.size() +
                               t.vndf.values.size() + t.luminance.values.size() + t.rgb.values.size();
    return sizeof(float) * floats;
}

std::string RglBrdf::describe() const {
    const Tensors& t = tensors_;
    const auto grid = [](const Grids& g) { return std::to_string(g.rows) + "x" + std::to_string(g.cols); };
    const std::string phi = aniso_ ? "anisotropic rgb " + std::to_string(t.phi_i.size()) + " phi_i x " : "isotropic rgb ";
    const std::string stored = svd_ ? "rgl_svd rank " + std::to_string(svd_->rank) +
                                          (svd_->dtype == SvdDtype::I8 ? " (int8)" : " (float16)") + " of " + std::to_string(svd_->slices) +
                                          " theta_i slices, expanded to " : "";
    return stored + "rgl " + phi + std::to_string(t.theta_i.size()) + " theta_i x " + grid(t.rgb) + " (vndf " +
           grid(t.vndf) + ", ndf " + grid(t.ndf) + ", sigma " + grid(t.sigma) + (t.jacobian ? "" : ", no jacobian") +
           (luminance_ ? "" : ", no luminance") + "; Mitsuba 'measured' evaluation and sampling)";
}

detail::KernelTables RglBrdf::kernel_tables() const {
    const Tensors& t = tensors_;
    const auto grid = [](const Grids& g) {
        return detail::GridTable{static_cast<int>(g.rows), static_cast<int>(g.cols), g.values.data()};
    };
    return {t.theta_i.data(), static_cast<int>(t.theta_i.size()), grid(t.ndf), grid(t.sigma), static_cast<int>(t.rgb.rows),
            static_cast<int>(t.rgb.cols), rgb_.data(), vndf_->tables(),
            luminance_ ? luminance_->tables() : detail::WarpTables{}, t.jacobian};
}

Rgb RglBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    Rgb f;
    eval_batch(&wi, &wo, &f, 1);
    return f;
}

void RglBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    if (aniso_) {
        for (std::size_t k = 0; k < n; ++k)
            out[k] = wi[k].z > 0.0 && wo[k].z > 0.0 ? aniso_->eval(wi[k], wo[k]) : Rgb{0.0, 0.0, 0.0};
        return;
    }
    detail::eval_pairs(simd_level(), kernel_tables(), wi, wo, out, n);
}

// The kernel sets the weight with the draw, so Brdf::sample does not evaluate it again (the anisotropic
// path leaves it to Brdf::sample).
BrdfSample RglBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    if (aniso_) return aniso_->sample(wo, u1, u2);
    const std::array<double, 2> u{u1, u2};
    BrdfSample s;
    sample_batch(&wo, &u, &s, 1);
    return s;
}

void RglBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    if (aniso_) {  // the base's draw (sample_above), then the weights from eval
        Brdf::sample_batch(wo, u, out, n);
        return;
    }
    detail::sample_pairs(simd_level(), kernel_tables(), wo, u, out, n);
}

double RglBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const {
    double p;
    pdf_batch(&wo, &wi, &p, 1);
    return p;
}

void RglBrdf::pdf_batch(const Vec3* wo, const Vec3* wi, double* out, std::size_t n) const {
    if (aniso_) {
        for (std::size_t k = 0; k < n; ++k) out[k] = wo[k].z > 0.0 && wi[k].z > 0.0 ? aniso_->pdf(wo[k], wi[k]) : 0.0;
        return;
    }
    detail::pdf_pairs(simd_level(), kernel_tables(), wo, wi, out, n);
}

}  // namespace brdfz::rgl
