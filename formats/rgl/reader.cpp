#include <algorithm>
#include <cmath>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "tensor_file.h"

namespace brdfz::rgl {
namespace {

using detail::DType;
using detail::Field;
using detail::TensorFile;

std::string shape_str(const std::vector<std::uint64_t>& shape) {
    std::string s;
    for (std::size_t k = 0; k < shape.size(); ++k) {
        if (k) s += 'x';
        s += std::to_string(shape[k]);
    }
    return shape.empty() ? "scalar" : s;
}

// A field Mitsuba's `measured` plugin requires, with its dtype and rank; FormatError otherwise.
const Field& require(const TensorFile& tf, const char* name, DType dtype, std::size_t rank) {
    const Field* f = tf.find(name);
    if (!f) throw FormatError(tf.path(), std::string("missing field '") + name + "'");
    if (f->dtype != dtype || f->shape.size() != rank)
        throw FormatError(tf.path(), std::string("field '") + name + "' is " + std::to_string(f->shape.size()) + "-d " +
                                         detail::dtype_name(f->dtype) + ", expected " + std::to_string(rank) + "-d " +
                                         detail::dtype_name(dtype));
    return *f;
}

void expect_shape(const TensorFile& tf, const Field& f, const std::vector<std::uint64_t>& expected) {
    if (f.shape != expected)
        throw FormatError(tf.path(), "field '" + f.name + "' has shape " + shape_str(f.shape) + ", expected " +
                                         shape_str(expected));
}

// A field whose last two dimensions are the rows and columns of its tables; the leading ones (at
// most {φi count, θi count, 3}, checked by the caller) count the slices.
Grids read_grids(const TensorFile& tf, const Field& f) {
    Grids g;
    const std::size_t rank = f.shape.size();
    for (std::size_t k = 0; k + 2 < rank; ++k) g.slices *= f.shape[k];
    g.rows = f.shape[rank - 2];
    g.cols = f.shape[rank - 1];
    g.values = tf.read_f32(f);
    return g;
}

std::string counts_str(const ValidityCounts& c, std::size_t total) {
    std::string s;
    const auto part = [&](std::size_t n, const char* what) {
        if (n) s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    part(c.negative, "negative");
    part(c.nan, "NaN");
    part(c.inf, "Inf");
    return s + " of " + std::to_string(total) + " values";
}

}  // namespace

ValidityCounts count_values(const std::vector<float>& values) {
    ValidityCounts c;
    for (float v : values) {
        if (std::isnan(v)) ++c.nan;
        else if (std::isinf(v)) ++c.inf;
        else ++(v < 0.0f ? c.negative : c.valid);
    }
    return c;
}

void check_renderable(const std::string& path, const Tensors& t) {
    const auto finite = [&](const char* field, const std::vector<float>& v, bool negatives_allowed, const char* why) {
        const ValidityCounts c = count_values(v);
        if (c.nan || c.inf || (c.negative && !negatives_allowed))
            throw FormatError(path, std::string("field '") + field + "' holds " + counts_str(c, v.size()) + ": " + why);
    };
    finite("ndf", t.ndf.values, false, "a microfacet density is finite and >= 0");
    finite("sigma", t.sigma.values, false, "a projected area is finite and > 0");
    const auto zeros = static_cast<std::size_t>(std::count(t.sigma.values.begin(), t.sigma.values.end(), 0.0f));
    if (zeros)
        throw FormatError(path, "field 'sigma' holds " + std::to_string(zeros) + " values of 0 (of " +
                                    std::to_string(t.sigma.values.size()) +
                                    "): f divides by the projected area, which must be > 0");
    finite("vndf", t.vndf.values, false, "a visible-normal density is finite and >= 0");
    finite("luminance", t.luminance.values, true, "the sampling density must be finite");
    const ValidityCounts rgb = count_values(t.rgb.values);
    if (rgb.valid == 0)
        throw FormatError(path, "field 'rgb' has no finite value >= 0 (" + std::to_string(rgb.negative) + " negative, " +
                                    std::to_string(rgb.nan) + " NaN, " + std::to_string(rgb.inf) + " Inf of " +
                                    std::to_string(t.rgb.values.size()) + "): nothing to render");
}

ReadResult read(const std::string& path) {
    const TensorFile tf(path);

    // Valid files this library does not handle; recognised before their shapes are checked,
    // since they differ from the RGB layout. Like Mitsuba, the `isotropic` field is not read: the
    // number of phi_i entries decides (aniso.h).
    if (tf.find("wavelengths") || tf.find("spectra"))
        throw UnsupportedError(path, "spectral RGL file ('wavelengths'/'spectra' fields): only RGB files are "
                                     "supported");
    const Field& phi_i = require(tf, "phi_i", DType::F32, 1);

    const Field& description = require(tf, "description", DType::U8, 1);
    const Field& jacobian = require(tf, "jacobian", DType::U8, 1);
    const Field& theta_i = require(tf, "theta_i", DType::F32, 1);
    const Field& ndf = require(tf, "ndf", DType::F32, 2);
    const Field& sigma = require(tf, "sigma", DType::F32, 2);
    const Field& vndf = require(tf, "vndf", DType::F32, 4);
    const Field& luminance = require(tf, "luminance", DType::F32, 4);
    const Field& rgb = require(tf, "rgb", DType::F32, 5);

    const std::uint64_t n_theta = theta_i.shape[0], n_phi = phi_i.shape[0];
    if (n_theta == 0) throw FormatError(path, "field 'theta_i' is empty");
    if (n_phi == 0) throw FormatError(path, "field 'phi_i' is empty");
    expect_shape(tf, jacobian, {1});
    expect_shape(tf, vndf, {n_phi, n_theta, vndf.shape[2], vndf.shape[3]});
    expect_shape(tf, rgb, {n_phi, n_theta, 3, rgb.shape[3], rgb.shape[3]});
    // The density of the sampler's first warp, over the same square as rgb.
    expect_shape(tf, luminance, {n_phi, n_theta, rgb.shape[3], rgb.shape[4]});

    ReadResult result;
    for (std::uint64_t d : rgb.shape) result.dims.push_back(static_cast<std::size_t>(d));
    const std::vector<std::uint8_t> text = tf.read_u8(description);
    result.description.assign(text.begin(), text.end());
    while (!result.description.empty() && result.description.back() == '\0') result.description.pop_back();

    Tensors t;
    if (n_phi > 1) t.phi_i = tf.read_f32(phi_i);
    t.theta_i = tf.read_f32(theta_i);
    t.ndf = read_grids(tf, ndf);
    t.sigma = read_grids(tf, sigma);
    t.vndf = read_grids(tf, vndf);
    t.luminance = read_grids(tf, luminance);
    t.rgb = read_grids(tf, rgb);
    t.jacobian = tf.read_u8(jacobian)[0] != 0;

    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (float v : t.rgb.values)
        if (std::isfinite(v)) {
            lo = std::min<double>(lo, v);
            hi = std::max<double>(hi, v);
        }
    result.min_value = lo <= hi ? lo : 0.0;
    result.max_value = lo <= hi ? hi : 0.0;
    result.counts = count_values(t.rgb.values);
    result.fields = {{"ndf", count_values(t.ndf.values)}, {"sigma", count_values(t.sigma.values)},
                     {"vndf", count_values(t.vndf.values)}};
    if (!t.luminance.values.empty()) result.fields.emplace_back("luminance", count_values(t.luminance.values));
    result.fields.emplace_back("rgb", result.counts);
    check_renderable(path, t);

    try {
        result.brdf = std::make_unique<RglBrdf>(std::move(t));
    } catch (const ValueError& e) {
        throw FormatError(path, e.what());
    }
    return result;
}

}  // namespace brdfz::rgl
