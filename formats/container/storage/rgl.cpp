// RGL storage: the tensors of an RGB RGL-EPFL material (Dupuy & Jakob 2018) as RglBrdf keeps them, so a
// .bsdf file converted to .brdfz evaluates bit-identically to the file. Datasets (float32, C order):
// theta_i [n], ndf [rows, cols], sigma [rows, cols], vndf [n, rows, cols], rgb [n, 3, rows, cols], and
// luminance [n, rows, cols] when the material has one (for sampling); attribute jacobian (0 or 1).
// An anisotropic material (feature rgl.anisotropic) adds phi_i [nφ], nφ >= 2, and every n above is
// nφ, n. formats/include/brdfz/formats/rgl.h explains the tensors.
#include <algorithm>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kRgl{"rgl", 1};
const Feature kAnisotropic{"rgl.anisotropic", 4};

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* rgl = dynamic_cast<const rgl::RglBrdf*>(&brdf);
    if (!rgl || rgl->svd()) return {};  // the compact form is rgl_svd.cpp's
    if (rgl->tensors().phi_i.size() > 1) return {kRgl, kAnisotropic};
    return {kRgl};
}

void write_grids(h5::WriteNode& rep, const char* name, const rgl::Grids& g, std::vector<std::uint64_t> lead) {
    lead.push_back(g.rows);
    lead.push_back(g.cols);
    rep.dataset(name, h5::DType::F32, lead, g.values.data());
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const rgl::Tensors& t = dynamic_cast<const rgl::RglBrdf&>(brdf).tensors();
    const std::uint64_t n = t.theta_i.size(), np = t.phi_i.size();
    // The slices' leading dimensions: n, or nφ, n.
    std::vector<std::uint64_t> lead{n};
    if (np > 1) {
        lead.insert(lead.begin(), np);
        rep.dataset("phi_i", h5::DType::F32, {np}, t.phi_i.data());
    }
    rep.attr("jacobian", std::uint64_t{t.jacobian});
    rep.dataset("theta_i", h5::DType::F32, {n}, t.theta_i.data());
    write_grids(rep, "ndf", t.ndf, {});
    write_grids(rep, "sigma", t.sigma, {});
    write_grids(rep, "vndf", t.vndf, lead);
    std::vector<std::uint64_t> rgb_lead = lead;
    rgb_lead.push_back(3);
    write_grids(rep, "rgb", t.rgb, rgb_lead);
    if (!t.luminance.values.empty()) write_grids(rep, "luminance", t.luminance, lead);
}

// A float32 dataset of the given rank whose leading dimensions (all but the last two) multiply to
// `slices`; read into a Grids.
rgl::Grids read_grids(const h5::ReadNode& rep, const char* name, std::size_t rank,
                      const std::vector<std::uint64_t>& lead) {
    const h5::Dataset d = rep.dataset(name);
    const auto& s = d.shape();
    if (d.type() != h5::DType::F32 || s.size() != rank || !std::equal(lead.begin(), lead.end(), s.begin()))
        throw FormatError(rep.file(), d.path() + ": unexpected element type or shape");
    rgl::Grids g;
    g.slices = 1;
    for (std::uint64_t l : lead) g.slices *= l;
    g.rows = s[rank - 2];
    g.cols = s[rank - 1];
    g.values.resize(d.count());
    d.read(g.values.data());
    return g;
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext&) {
    rgl::Tensors t;
    const std::uint64_t jacobian = rep.u64("jacobian");
    if (jacobian > 1) throw FormatError(rep.file(), rep.path() + ": attribute 'jacobian' is not 0 or 1");
    t.jacobian = jacobian == 1;
    const h5::Dataset theta = rep.dataset("theta_i");
    if (theta.type() != h5::DType::F32 || theta.shape().size() != 1)
        throw FormatError(rep.file(), theta.path() + ": expected a float32 vector");
    t.theta_i.resize(theta.count());
    theta.read(t.theta_i.data());
    const std::uint64_t n = t.theta_i.size();
    std::vector<std::uint64_t> lead{n};
    if (rep.has("phi_i")) {
        const h5::Dataset phi = rep.dataset("phi_i");
        if (phi.type() != h5::DType::F32 || phi.shape().size() != 1 || phi.count() < 2)
            throw FormatError(rep.file(), phi.path() + ": expected a float32 vector of at least 2 values");
        t.phi_i.resize(phi.count());
        phi.read(t.phi_i.data());
        lead.insert(lead.begin(), t.phi_i.size());
    }
    const std::size_t rank = lead.size() + 2;
    t.ndf = read_grids(rep, "ndf", 2, {});
    t.sigma = read_grids(rep, "sigma", 2, {});
    t.vndf = read_grids(rep, "vndf", rank, lead);
    std::vector<std::uint64_t> rgb_lead = lead;
    rgb_lead.push_back(3);
    t.rgb = read_grids(rep, "rgb", rank + 1, rgb_lead);
    if (rep.has("luminance")) t.luminance = read_grids(rep, "luminance", rank, lead);
    rgl::check_renderable(rep.file(), t);
    try {
        return std::make_unique<rgl::RglBrdf>(std::move(t));
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

// As the RGL reader counts the file's `rgb` values (the object keeps non-finite ones as 0).
void source_info(const Brdf& brdf, SourceInfo& info) {
    const rgl::Tensors& t = dynamic_cast<const rgl::RglBrdf&>(brdf).tensors();
    info.dims = {std::max<std::size_t>(t.phi_i.size(), 1), t.theta_i.size(), 3, t.rgb.rows, t.rgb.cols};
    info.dims_of = "rgb tensor of the RGL file";
    info.counts = {};
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (float v : t.rgb.values) {
        ++(v < 0.0f ? info.counts.negative : info.counts.valid);
        lo = std::min<double>(lo, v);
        hi = std::max<double>(hi, v);
    }
    info.min_value = lo <= hi ? lo : 0.0;
    info.max_value = lo <= hi ? hi : 0.0;
}

}  // namespace

void register_rgl(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"rgl", {kRgl, kAnisotropic}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
