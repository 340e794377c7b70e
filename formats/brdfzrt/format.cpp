// The runtime layout (formats/SPEC.md §6, brdfz/formats/runtime_layout.h) in the format registry: brdfz
// writes it from any material, and reads it back through brdfz::runtime (what a renderer runs), so
// `brdfz info`, `eval`, `diff` and `sample` see exactly what the runtime computes.
#include <memory>

#include "brdfz/errors.h"
#include "brdfz/formats/registry.h"
#include "brdfz/formats/runtime_layout.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/runtime/layout.h"
#include "brdfz/runtime/runtime.h"
#include "brdfzrt/runtime_brdf.h"
#include "detail/examples.h"

namespace brdfz::formats {
namespace {

Loaded read(const std::string& path, const LoadOptions&) {
    std::string error;
    runtime::Material m = runtime::Material::open(path, &error);
    if (!m) throw FormatError(path, error.substr(error.find(": ") == std::string::npos ? 0 : error.find(": ") + 2));
    Loaded out;
    out.info.format = "brdfzrt";
    out.info.dims = {m.nbytes()};
    out.info.dims_of = "bytes of the runtime layout";
    out.info.has_range = false;
    out.brdf = std::make_unique<RuntimeBrdf>(std::move(m));
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions&) {
    runtime_layout::write(path, brdf);
    return {};
}

bool sniff(std::string_view head, std::uintmax_t) {
    return head.size() >= 8 && head.compare(0, 8, std::string_view(reinterpret_cast<const char*>(runtime::layout::kMagic), 8)) == 0;
}

void examples(const std::string& dir) {
    runtime_layout::write(dir + "/table.brdfzrt", TabularBrdf(detail::example_table({2, 3, 4})));
    runtime_layout::write(dir + "/model.brdfzrt", AnalyticBrdf("lambert+ggx", {0.3, 0.25, 0.2, 0.6, 0.6, 0.6, 0.35, 0.04}));
}

}  // namespace

void register_brdfzrt(std::vector<Format>& out) {
    out.push_back({"brdfzrt",
                   "brdfz runtime layout: a material's arrays and sampler, flat, as brdfz::runtime and GPUs read them",
                   {".brdfzrt"},
                   sniff,
                   read,
                   nullptr,
                   write,
                   examples});
}

}  // namespace brdfz::formats
