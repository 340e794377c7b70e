// Analytic model files (brdfz/formats/model_json.h, docs/model-json.md) in the format registry.
#include <algorithm>

#include "brdfz/errors.h"
#include "brdfz/formats/model_json.h"
#include "brdfz/formats/registry.h"
#include "detail/examples.h"

namespace brdfz::formats {
namespace {

// Dims is the model's parameter count, the range that of its parameter values.
Loaded read(const std::string& path, const LoadOptions&) {
    auto model = std::make_unique<AnalyticBrdf>(model_json::read(path));
    Loaded out;
    out.info.format = "json";
    out.info.dims = {model->params().size()};
    out.info.dims_of = "parameters";
    out.info.counts.valid = model->params().size();
    const auto [lo, hi] = std::minmax_element(model->params().begin(), model->params().end());
    out.info.min_value = *lo;
    out.info.max_value = *hi;
    out.brdf = std::move(model);
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions&) {
    const auto* model = dynamic_cast<const AnalyticBrdf*>(&brdf);
    if (!model) throw UnsupportedError(path, "only analytic models can be written as .json (brdfz fit makes them)");
    model_json::write(path, *model);
    ValidityCounts written;
    written.valid = model->params().size();
    return written;
}

bool sniff(std::string_view head, std::uintmax_t) {
    const std::size_t start = head.find_first_not_of(" \t\r\n");
    return start != std::string_view::npos && head[start] == '{' && head.find("\"brdfz-analytic\"") != std::string_view::npos;
}

void examples(const std::string& dir) {
    detail::write_text(dir + "/a.json",
                       "{\"format\": \"brdfz-analytic\", \"version\": 1, \"model\": \"lambert+ggx\", \"parameters\": "
                       "{\"lambert.rho_r\": 0.1, \"lambert.rho_g\": 0.2, \"lambert.rho_b\": 0.3, \"ggx.ks_r\": 1, "
                       "\"ggx.ks_g\": 1, \"ggx.ks_b\": 1, \"ggx.alpha\": 0.1, \"ggx.f0\": 0.04}, \"provenance\": "
                       "{\"source\": \"seed\"}}\n");
}

}  // namespace

void register_json(std::vector<Format>& out) {
    out.push_back({"json", "analytic model (docs/model-json.md)", {".json"}, sniff, read, nullptr, write, examples});
}

}  // namespace brdfz::formats
