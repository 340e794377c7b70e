// RGL-EPFL tensor files (brdfz/formats/rgl.h, rgl_writer.h) in the format registry.
#include "brdfz/formats/registry.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/coated_diffuse.h"

namespace brdfz::formats {
namespace {

Loaded read(const std::string& path, const LoadOptions&) {
    rgl::ReadResult r = rgl::read(path);
    Loaded out;
    out.info.format = "rgl";
    out.info.dims = std::move(r.dims);
    out.info.counts = r.counts;
    out.info.min_value = r.min_value;
    out.info.max_value = r.max_value;
    out.info.fields = std::move(r.fields);
    out.brdf = std::move(r.brdf);
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    ValidityCounts written;
    rgl::WriteOptions w;
    w.n_phi_i = options.rgl_phi_i;
    written.valid = rgl::write(path, brdf, w);
    return written;
}

bool sniff(std::string_view head, std::uintmax_t) { return head.substr(0, 12) == std::string_view("tensor_file\0", 12); }

// A small file of the writer's parameterisation of a built-in material.
void examples(const std::string& dir) {
    rgl::WriteOptions w;
    w.n_theta_i = 3;
    w.vndf_resolution = 4;
    w.rgb_resolution = 4;
    w.ndf_resolution = 4;
    rgl::write(dir + "/a.bsdf", CoatedDiffuse(), w);
}

}  // namespace

void register_rgl(std::vector<Format>& out) {
    out.push_back({"rgl", "RGL-EPFL tensor file (RGB, isotropic or anisotropic; Dupuy & Jakob 2018), as Mitsuba 3 `measured` reads it",
                   {".bsdf"}, sniff, read, nullptr, write, examples});
}

}  // namespace brdfz::formats
