// Analytic storage: a model string (brdfz/repr/analytic/model.h, e.g. "lambert+ggx") and its
// parameters as a float64 dataset "params" [k], with the parameter names as attribute "param_names"
// so the file describes itself. Reading parses the model, checks that its parameter names are the
// stored ones (a changed parameterisation is refused, not misread) and validates the values. A model
// sampled by a compact sampler stores its tables in a group "sampler" (container/sampler.h); without
// the group the model samples by its lobe mixture, as files written before the group existed do.
#include <algorithm>
#include <optional>

#include "brdfz/errors.h"
#include "brdfz/repr/analytic/model.h"
#include "container/sampler.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kAnalytic{"analytic", 1};

std::vector<Feature> needs(const Brdf& brdf) {
    if (!dynamic_cast<const AnalyticBrdf*>(&brdf)) return {};
    return {kAnalytic};
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const auto& a = dynamic_cast<const AnalyticBrdf&>(brdf);
    const Model& m = a.model();
    std::vector<std::string> names;
    for (std::size_t k = 0; k < m.size(); ++k) names.push_back(m.name(k));
    rep.attr("model", m.text());
    rep.attr("param_names", std::span<const std::string>(names));
    rep.dataset("params", h5::DType::F64, {m.size()}, a.params().data());
    if (const CompactSampler* c = a.compact_sampler()) write_sampler(rep, SamplerKind::Compact, c);
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext&) {
    const std::string text = rep.str("model");
    Model model = [&] {
        try {
            return Model::parse(text);
        } catch (const ValueError& e) {
            // The structure is checksummed, so this is a model from a newer brdfz, not damage.
            throw UnsupportedError(rep.file(), rep.path() + ": model '" + text + "': " + e.what());
        }
    }();
    const std::vector<std::string> names = rep.strs("param_names");
    bool same = names.size() == model.size();
    for (std::size_t k = 0; same && k < names.size(); ++k) same = names[k] == model.name(k);
    if (!same)
        throw UnsupportedError(rep.file(), rep.path() + ": the parameters of model '" + text +
                                               "' are not the ones this brdfz knows (a different version)");
    const h5::Dataset params = rep.dataset("params");
    if (params.type() != h5::DType::F64 || params.shape() != std::vector<std::uint64_t>{model.size()})
        throw FormatError(rep.file(), params.path() + ": expected float64 [" + std::to_string(model.size()) + "]");
    std::vector<double> values(model.size());
    params.read(values.data());
    std::optional<CompactSampler> compact;
    if (rep.has("sampler")) {
        compact = read_sampler(rep).compact;
        if (!compact) throw FormatError(rep.file(), rep.path() + "/sampler: an analytic model's sampler is compact or absent");
    }
    try {
        if (compact) return std::make_unique<AnalyticBrdf>(std::move(model), std::move(values), std::move(*compact));
        return std::make_unique<AnalyticBrdf>(std::move(model), std::move(values));
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

void source_info(const Brdf& brdf, SourceInfo& info) {
    const std::span<const double> p = dynamic_cast<const AnalyticBrdf&>(brdf).params();
    info.dims = {p.size()};
    info.dims_of = "parameters";
    info.counts = {};
    info.counts.valid = p.size();
    const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
    info.min_value = p.empty() ? 0.0 : *lo;
    info.max_value = p.empty() ? 0.0 : *hi;
}

}  // namespace

void register_analytic(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"analytic", {kAnalytic}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
