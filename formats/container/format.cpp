// The .brdfz container (brdfz/formats/container.h, formats/SPEC.md) in the format registry.
#include "brdfz/formats/container.h"
#include "brdfz/formats/registry.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/tabular.h"
#include "container/storage.h"
#include "detail/examples.h"

namespace brdfz::formats {
namespace {

Loaded read(const std::string& path, const LoadOptions& options) {
    container::ReadResult r = container::read(path, options.lookup);
    Loaded out;
    out.info.format = "brdfz";
    out.info.counts = r.meta.achieved.counts;
    if (const auto* module = container::detail::find_storage(r.meta.representation))
        module->source_info(*r.brdf, out.info);
    out.brdf = std::move(r.brdf);
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    container::WriteOptions w;
    w.source = options.source;
    w.source_format = options.source_format;
    w.grid = options.grid;
    w.threads = options.threads;
    w.progress = options.progress;
    w.build_spec = options.build_spec;
    w.source_metrics = options.source_metrics;
    return container::write(path, brdf, w).counts;
}

// The envelope's magic (formats/SPEC.md).
bool sniff(std::string_view head, std::uintmax_t) { return head.substr(0, 8) == std::string_view("\x89" "BRDFZ\r\n", 8); }

void examples(const std::string& dir) {
    container::write(dir + "/tabular.brdfz", TabularBrdf(detail::example_table({2, 3, 4})));
    container::WriteOptions coarse;
    coarse.grid = GridSpec{2, 2, 2};
    container::write(dir + "/tabulated.brdfz", CoatedDiffuse(), coarse);
    rgl::WriteOptions w;
    w.n_theta_i = 3;
    w.vndf_resolution = 4;
    w.rgb_resolution = 4;
    w.ndf_resolution = 4;
    container::write(dir + "/rgl.brdfz", rgl::RglBrdf(rgl::derive(CoatedDiffuse(), w)));
    // rgl_svd's compact forms, of tensors whose vndf is their ndf's, as a measurement's is.
    rgl::Tensors measured = rgl::derive(CoatedDiffuse(), w);
    measured.vndf = rgl::derived_vndf(measured.theta_i, measured.ndf, measured.vndf.rows, measured.vndf.cols);
    container::write(dir + "/rgl_svd.brdfz", *rgl::make_svd_brdf(rgl::factor(measured, 8, 1.0)));
    container::write(dir + "/rgl_svd_i8.brdfz", *rgl::make_svd_brdf(rgl::factor(measured, 8, 1.0, rgl::SvdDtype::I8)));
}

}  // namespace

void register_container(std::vector<Format>& out) {
    out.push_back({"brdfz", "brdfz container: any representation, versioned, checksummed (formats/SPEC.md)",
                   {".brdfz"}, sniff, read, nullptr, write, examples});
}

}  // namespace brdfz::formats
