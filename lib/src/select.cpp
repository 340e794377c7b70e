#include "brdfz/select.h"

#include <cmath>
#include <cstdio>

#include "brdfz/errors.h"

namespace brdfz {
namespace {

template <typename Source>
Trial measure(const Source& source, const std::string& spec, const TrialOptions& options) {
    Compressed c = compress(source, spec, options.compress);
    Trial t;
    t.spec = std::move(c.spec);
    t.describe = c.brdf->describe();
    t.bytes = c.brdf->nbytes();
    t.metrics = compare(source, *c.brdf, options.metrics);
    if (options.measure_speed) t.eval_rate = eval_rate(*c.brdf);
    t.build_seconds = c.build_seconds;
    t.notes = std::move(c.notes);
    t.brdf = std::move(c.brdf);
    return t;
}

}  // namespace

Trial trial(const Brdf& source, const std::string& spec, const TrialOptions& options) {
    return measure(source, spec, options);
}

Trial trial(const MeasurementSet& source, const std::string& spec, const TrialOptions& options) {
    return measure(source, spec, options);
}

std::vector<std::string> default_candidates() {
    return {
        "analytic:lambert+ggx",     "analytic:lambert+ggx+ggx", "tabular:res=16x16x32",
        "tabular:res=32x32x64",     "tabular:res=45x45x90",     "tabular:res=90x90x180",
    };
}

Selection select_representation(const Brdf& source, const SelectOptions& options) {
    if (!(std::isfinite(options.max_error) && options.max_error > 0.0))
        throw ValueError("select: the error budget must be a finite number > 0");
    const std::vector<std::string> candidates = options.candidates.empty() ? default_candidates() : options.candidates;
    const std::optional<Scene> judge =
        options.scene ? options.scene
                      : options.metric == SceneMetric::Image ? std::optional<Scene>(build_scene(default_scene())) : std::nullopt;
    Selection out;
    for (const std::string& spec : candidates) {
        Candidate c;
        try {
            c.trial = trial(source, spec, options.trial);
            if (judge)
                c.error = scene_error(source, *c.trial.brdf, *judge, options.metric);
            else
                c.error = options.metric == SceneMetric::Cos ? c.trial.metrics.cos_rmse_rel.mean : c.trial.metrics.log_rmse.mean;
            char buf[96];
            if (!std::isfinite(c.error)) {
                c.reason = "error is not finite";
            } else if (c.error > options.max_error) {
                std::snprintf(buf, sizeof buf, "error %.4g > budget %.4g", c.error, options.max_error);
                c.reason = buf;
            } else {
                c.accepted = true;
                c.reason = "meets the budget";
            }
        } catch (const Error& e) {
            c.trial.spec = spec;
            c.error = std::nan("");
            c.reason = std::string("failed: ") + e.what();
        }
        if (!c.accepted) c.trial.brdf.reset();  // only the chosen one is kept in memory
        out.tried.push_back(std::move(c));
        if (options.on_candidate) options.on_candidate(out.tried.back());
        if (out.tried.back().accepted) {
            out.chosen = static_cast<int>(out.tried.size()) - 1;
            break;
        }
    }
    return out;
}

}  // namespace brdfz
