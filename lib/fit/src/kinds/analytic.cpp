// Kind `analytic`: analytic lobes fitted with Ceres (fit/fit.h), from a BRDF or from scattered
// measurements.
#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"

namespace brdfz::kinds {
namespace {

// What the kind's keys ask of the fit and of the result's sampler.
struct AnalyticOptions {
    FitOptions fit;
    bool compact = true;  // sampler=compact, else the lobe mixture
    int threads = 1;
};

AnalyticOptions analytic_options(const ReprSpec& spec, const CompressOptions& options) {
    if (spec.positional().empty())
        throw ValueError("analytic: name the model, e.g. analytic:lambert+ggx");
    AnalyticOptions out;
    out.compact = spec.get_choice("sampler", "compact", {"compact", "lobes"}) == "compact";
    out.threads = options.threads;
    FitOptions& fit_options = out.fit;
    fit_options.loss = parse_fit_loss(spec.get_choice("loss", "log", {"log", "cos", "cbrt"}));
    fit_options.starts = spec.get_int("starts", fit_options.starts, 1, FitOptions::kMaxStarts);
    fit_options.seed = static_cast<std::uint64_t>(spec.get_int("seed", 1, 0, 1 << 30));
    spec.finish();
    fit_options.threads = options.threads;
    fit_options.progress = options.progress;
    return out;
}

Compressed from_fit(FitResult fitted, const AnalyticOptions& options) {
    Compressed out;
    out.notes.push_back(std::string("fit ") + fit_status_name(fitted.report.status) + ": " + fitted.report.message);
    for (const std::string& w : fitted.report.warnings) out.notes.push_back(w);
    const AnalyticBrdf& m = fitted.model;
    if (options.compact) {
        CompactSamplerOptions sampler;
        sampler.threads = options.threads;
        out.brdf = AnalyticBrdf::with_compact_sampler(m.model(), {m.params().begin(), m.params().end()}, sampler);
    } else {
        out.brdf = std::make_unique<AnalyticBrdf>(std::move(fitted.model));
    }
    return out;
}

Compressed build(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const AnalyticOptions o = analytic_options(spec, options);
    return from_fit(fit(source, spec.positional(), o.fit), o);
}

Compressed build_measurements(const MeasurementSet& source, const ReprSpec& spec, const CompressOptions& options) {
    const AnalyticOptions o = analytic_options(spec, options);
    return from_fit(fit(source, spec.positional(), o.fit), o);
}

}  // namespace

void register_analytic(std::vector<ReprKind>& out) {
    out.push_back({"analytic",
                   "analytic lobes fitted with Ceres, lobes joined by + (docs/fitting.md, docs/model-json.md)",
                   "MODEL",
                   {{"loss", "log", "log|cos|cbrt: the residual's transform"},
                    {"starts", "8", "multi-start count, 1-1000"},
                    {"seed", "1", "seed of the starts"},
                    {"sampler", "compact",
                     "compact|lobes: the importance sampler, ~14 KB of CDFs stored with the model (weights vary "
                     "less), or the mixture of the lobes' own samplers (no data)"}},
                   build,
                   build_measurements});
}

}  // namespace brdfz::kinds
