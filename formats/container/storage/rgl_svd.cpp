// rgl_svd storage: an isotropic RGL-EPFL material's compact form (brdfz/formats/rgl_svd.h), what the
// object keeps; the tensors it evaluates are expanded from it when it is read. Datasets: theta_i
// (float32 [n]), ndf and sigma (float16 [rows, cols] or [1, cols], the one row repeated to the rows of
// attributes ndf_shape and sigma_shape, times 2^ndf_exponent, 2^sigma_exponent), u (float16
// [slices·cols, rank]) and v (float16 [3·rows, rank]), or u and v as int8 times steps u_scale (float16
// [slices, rank]: each slice's in each factor, times 2^u_scale_exponent) and v_scale (float16 [3, rank]:
// each channel's, times 2^v_scale_exponent);
// attributes jacobian and luminance (0 or 1), slices, vndf_shape [rows, cols], and rgb_floor [3] (each
// channel's least value, feature rgl.svd.floor; absent in files of container version 8: no floor).
#include <cmath>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl_svd.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kRglSvd{"rgl.svd", 8};
const Feature kInt8{"rgl.svd.int8", 9};
const Feature kFloor{"rgl.svd.floor", 9};

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* rgl = dynamic_cast<const rgl::RglBrdf*>(&brdf);
    if (!rgl || !rgl->svd()) return {};
    const rgl::SvdTensors& s = *rgl->svd();
    std::vector<Feature> out{kRglSvd};
    if (s.dtype == rgl::SvdDtype::I8) out.push_back(kInt8);
    if (s.has_floor()) out.push_back(kFloor);
    return out;
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const rgl::SvdTensors& s = *dynamic_cast<const rgl::RglBrdf&>(brdf).svd();
    rep.attr("jacobian", std::uint64_t{s.jacobian});
    rep.attr("luminance", std::uint64_t{s.luminance});
    rep.attr("slices", std::uint64_t{s.slices});
    const std::uint64_t vndf_shape[] = {s.vndf_rows, s.vndf_cols};
    rep.attr("vndf_shape", std::span<const std::uint64_t>(vndf_shape));
    rep.attr("ndf_exponent", static_cast<double>(s.ndf_exponent));
    rep.attr("sigma_exponent", static_cast<double>(s.sigma_exponent));
    if (s.has_floor()) {
        const double floor[] = {s.floor[0], s.floor[1], s.floor[2]};
        rep.attr("rgb_floor", std::span<const double>(floor));
    }
    rep.dataset("theta_i", h5::DType::F32, {s.theta_i.size()}, s.theta_i.data());
    const std::uint64_t ndf_shape[] = {s.ndf_rows, s.ndf_cols}, sigma_shape[] = {s.sigma_rows, s.sigma_cols};
    rep.attr("ndf_shape", std::span<const std::uint64_t>(ndf_shape));
    rep.attr("sigma_shape", std::span<const std::uint64_t>(sigma_shape));
    rep.dataset("ndf", h5::DType::F16, {s.ndf.size() / s.ndf_cols, s.ndf_cols}, s.ndf.data());
    rep.dataset("sigma", h5::DType::F16, {s.sigma.size() / s.sigma_cols, s.sigma_cols}, s.sigma.data());
    if (s.dtype == rgl::SvdDtype::F16) {
        rep.dataset("u", h5::DType::F16, {s.slices * s.cols, s.rank}, s.u.data());
        rep.dataset("v", h5::DType::F16, {3 * s.rows, s.rank}, s.v.data());
    } else {
        rep.dataset("u", h5::DType::I8, {s.slices * s.cols, s.rank}, s.u8.data());
        rep.dataset("v", h5::DType::I8, {3 * s.rows, s.rank}, s.v8.data());
        rep.dataset("u_scale", h5::DType::F16, {s.slices, s.rank}, s.u_scale.data());
        rep.dataset("v_scale", h5::DType::F16, {3, s.rank}, s.v_scale.data());
        rep.attr("u_scale_exponent", static_cast<double>(s.u_scale_exponent));
        rep.attr("v_scale_exponent", static_cast<double>(s.v_scale_exponent));
    }
}

// Bound on the values a dataset holds and on the expanded tensors' (floats).
constexpr std::uint64_t kMaxValues = std::uint64_t{1} << 26;

// A dataset of the given type and rank, its size bounded before reading.
h5::Dataset checked(const h5::ReadNode& rep, const char* name, h5::DType type, std::size_t rank) {
    h5::Dataset d = rep.dataset(name);
    const auto& s = d.shape();
    bool ok = d.type() == type && s.size() == rank && d.count() <= kMaxValues;
    for (std::uint64_t side : s) ok = ok && side >= 1;
    if (!ok) throw FormatError(rep.file(), d.path() + ": unexpected element type or shape");
    return d;
}

int exponent(const h5::ReadNode& rep, const char* name) {
    const double e = rep.f64(name);
    if (!(std::fabs(e) <= 200.0) || e != std::floor(e))
        throw FormatError(rep.file(), rep.path() + ": attribute '" + name + "' is not an integer in [-200, 200]");
    return static_cast<int>(e);
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext&) {
    rgl::SvdTensors s;
    const std::uint64_t jacobian = rep.u64("jacobian"), luminance = rep.u64("luminance");
    if (jacobian > 1 || luminance > 1)
        throw FormatError(rep.file(), rep.path() + ": attribute 'jacobian' or 'luminance' is not 0 or 1");
    s.jacobian = jacobian == 1, s.luminance = luminance == 1;
    const auto shape = [&](const char* name, std::size_t& rows, std::size_t& cols) {
        const std::vector<std::uint64_t> v = rep.u64s(name);
        if (v.size() != 2 || v[0] > 4096 || v[1] > 4096)
            throw FormatError(rep.file(), rep.path() + ": attribute '" + name + "' is not two sizes of at most 4096");
        rows = v[0], cols = v[1];
    };
    shape("vndf_shape", s.vndf_rows, s.vndf_cols);
    shape("ndf_shape", s.ndf_rows, s.ndf_cols);
    shape("sigma_shape", s.sigma_rows, s.sigma_cols);
    s.slices = rep.u64("slices");
    if (rep.has_attr("rgb_floor")) {
        const std::vector<double> floor = rep.f64s("rgb_floor");
        if (floor.size() != 3) throw FormatError(rep.file(), rep.path() + ": attribute 'rgb_floor' is not three values");
        for (std::size_t c = 0; c < 3; ++c) {
            if (!(std::fabs(floor[c]) <= 3e38)) throw FormatError(rep.file(), rep.path() + ": attribute 'rgb_floor' is not finite");
            s.floor[c] = static_cast<float>(floor[c]);
        }
    }
    s.ndf_exponent = exponent(rep, "ndf_exponent");
    s.sigma_exponent = exponent(rep, "sigma_exponent");
    s.dtype = rep.dataset("u").type() == h5::DType::I8 ? rgl::SvdDtype::I8 : rgl::SvdDtype::F16;
    const h5::DType factor_type = s.dtype == rgl::SvdDtype::I8 ? h5::DType::I8 : h5::DType::F16;
    const h5::Dataset theta = checked(rep, "theta_i", h5::DType::F32, 1), ndf = checked(rep, "ndf", h5::DType::F16, 2),
                      sigma = checked(rep, "sigma", h5::DType::F16, 2), u = checked(rep, "u", factor_type, 2),
                      v = checked(rep, "v", factor_type, 2);
    s.rank = v.shape()[1];
    if (s.dtype == rgl::SvdDtype::I8) {
        const h5::Dataset us = checked(rep, "u_scale", h5::DType::F16, 2), vs = checked(rep, "v_scale", h5::DType::F16, 2);
        s.u_scale_exponent = exponent(rep, "u_scale_exponent");
        s.v_scale_exponent = exponent(rep, "v_scale_exponent");
        if (us.shape()[0] != s.slices || us.shape()[1] != s.rank || vs.shape()[0] != 3 || vs.shape()[1] != s.rank)
            throw FormatError(rep.file(), rep.path() + ": the factors' shapes disagree");
        s.u_scale.resize(us.count());
        us.read(s.u_scale.data());
        s.v_scale.resize(vs.count());
        vs.read(s.v_scale.data());
    }
    if (u.shape()[1] != s.rank || s.slices < 1 || u.shape()[0] % s.slices != 0 || v.shape()[0] % 3 != 0)
        throw FormatError(rep.file(), rep.path() + ": the factors' shapes disagree");
    s.rows = v.shape()[0] / 3, s.cols = u.shape()[0] / s.slices;
    // The expansion's own checks bound every side before anything of the tensors' size is allocated.
    const std::uint64_t expanded = theta.count() * (s.vndf_rows * s.vndf_cols + 4 * s.rows * s.cols);
    if (s.rows > 4096 || s.cols > 4096 || expanded > kMaxValues)
        throw FormatError(rep.file(), rep.path() + ": the expanded tensors would be too large");
    s.theta_i.resize(theta.count());
    theta.read(s.theta_i.data());
    s.ndf.resize(ndf.count());
    ndf.read(s.ndf.data());
    s.sigma.resize(sigma.count());
    sigma.read(s.sigma.data());
    if (s.dtype == rgl::SvdDtype::I8) {
        s.u8.resize(u.count());
        u.read(s.u8.data());
        s.v8.resize(v.count());
        v.read(s.v8.data());
    } else {
        s.u.resize(u.count());
        u.read(s.u.data());
        s.v.resize(v.count());
        v.read(s.v.data());
    }
    for (std::size_t i = 0; i < s.theta_i.size(); ++i)
        if (!std::isfinite(s.theta_i[i]) || s.theta_i[i] < 0.0f || s.theta_i[i] > 1.6f ||
            (i > 0 && !(s.theta_i[i] > s.theta_i[i - 1])))
            throw FormatError(rep.file(), rep.path() + "/theta_i: not increasing angles in [0, pi/2]");
    try {
        rgl::Tensors t = rgl::expand(s);
        rgl::check_renderable(rep.file(), t);
        return std::make_unique<rgl::RglBrdf>(std::move(t), std::make_shared<const rgl::SvdTensors>(std::move(s)));
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

void source_info(const Brdf& brdf, SourceInfo& info) {
    const rgl::SvdTensors& s = *dynamic_cast<const rgl::RglBrdf&>(brdf).svd();
    info.dims = {s.slices * s.cols, 3 * s.rows, s.rank};
    info.dims_of = "rgb tensor factors: rows (theta_i slice, column) x columns (channel, grid row), rank";
    info.has_range = false;
}

}  // namespace

void register_rgl_svd(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"rgl_svd", {kRglSvd, kInt8, kFloor}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
