// RGL storage: the tensors of an isotropic RGB RGL-EPFL material (Dupuy & Jakob 2018) as RglBrdf keeps
// them, so a .bsdf file converted to .brdfz evaluates bit-identically to the file. Datasets (float32,
// C order): theta_i [n], ndf [rows, cols], sigma [rows, cols], vndf [n, rows, cols],
// rgb [n, 3, rows, cols], and luminance [n, rows, cols] when the material has one (for sampling);
// attribute jacobian (0 or 1). formats/include/brdfz/formats/rgl.h explains the tensors.
#include <algorithm>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kRgl{"rgl", 1};

std::vector<Feature> needs(const Brdf& brdf) {
    if (!dynamic_cast<const rgl::RglBrdf*>(&brdf)) return {};
    return {kRgl};
}

void write_grids(h5::WriteNode& rep, const char* name, const rgl::Grids& g, std::vector<std::uint64_t> lead) {
    lead.push_back(g.rows);
    lead.push_back(g.cols);
    rep.dataset(name, h5::DType::F32, lead, g.values.data());
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const rgl::Tensors& t = dynamic_cast<const rgl::RglBrdf&>(brdf).tensors();
    const std::uint64_t n = t.theta_i.size();
    rep.attr("jacobian", std::uint64_t{t.jacobian});
    rep.dataset("theta_i", h5::DType::F32, {n}, t.theta_i.data());
    write_grids(rep, "ndf", t.ndf, {});
    write_grids(rep, "sigma", t.sigma, {});
    write_grids(rep, "vndf", t.vndf, {n});
    write_grids(rep, "rgb", t.rgb, {n, 3});
    if (!t.luminance.values.empty()) write_grids(rep, "luminance", t.luminance, {n});
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
    t.ndf = read_grids(rep, "ndf", 2, {});
    t.sigma = read_grids(rep, "sigma", 2, {});
    t.vndf = read_grids(rep, "vndf", 3, {n});
    t.rgb = read_grids(rep, "rgb", 4, {n, 3});
    if (rep.has("luminance")) t.luminance = read_grids(rep, "luminance", 3, {n});
    try {
        return std::make_unique<rgl::RglBrdf>(std::move(t));
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

// As the RGL reader counts the file's `rgb` values (the object keeps non-finite ones as 0).
void source_info(const Brdf& brdf, SourceInfo& info) {
    const rgl::Tensors& t = dynamic_cast<const rgl::RglBrdf&>(brdf).tensors();
    info.dims = {1, t.theta_i.size(), 3, t.rgb.rows, t.rgb.cols};
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
    static const StorageModule m{"rgl", {kRgl}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
