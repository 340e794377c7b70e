#include "brdfz/fit/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <numbers>

#include "brdfz/errors.h"
#include "detail/parallel.h"
#include "detail/random.h"
#include "residuals.h"

namespace brdfz {

FitLoss parse_fit_loss(const std::string& name) {
    if (name == "cos") return FitLoss::Cosine;
    if (name == "log") return FitLoss::Log;
    if (name == "cbrt") return FitLoss::Cbrt;
    throw ValueError("unknown fit loss '" + name + "' (expected cos, log or cbrt)");
}

const char* fit_loss_name(FitLoss loss) {
    switch (loss) {
        case FitLoss::Cosine: return "cos";
        case FitLoss::Log: return "log";
        case FitLoss::Cbrt: return "cbrt";
    }
    return "?";
}

RobustLoss parse_robust_loss(const std::string& name) {
    if (name == "none") return RobustLoss::None;
    if (name == "huber") return RobustLoss::Huber;
    if (name == "cauchy") return RobustLoss::Cauchy;
    throw ValueError("unknown robust loss '" + name + "' (expected none, huber or cauchy)");
}

const char* robust_loss_name(RobustLoss loss) {
    switch (loss) {
        case RobustLoss::None: return "none";
        case RobustLoss::Huber: return "huber";
        case RobustLoss::Cauchy: return "cauchy";
    }
    return "?";
}

const char* fit_status_name(FitStatus status) {
    switch (status) {
        case FitStatus::Converged: return "converged";
        case FitStatus::HitBounds: return "hit_bounds";
        case FitStatus::NoConvergence: return "no_convergence";
        case FitStatus::InsufficientData: return "insufficient_data";
    }
    return "?";
}

namespace {

using Clock = std::chrono::steady_clock;
using namespace fitting;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Channel of a per-channel parameter ("ks_g" -> 1), or -1.
int channel_of(std::string_view name) {
    if (name.size() < 2 || name[name.size() - 2] != '_') return -1;
    switch (name.back()) {
        case 'r': return 0;
        case 'g': return 1;
        case 'b': return 2;
    }
    return -1;
}

// The problem in solver variables: bounds, and conversions to and from model parameters.
struct Space {
    const Model& model;
    Setup setup;
    std::vector<double> lo, hi;  // bounds of the solver variables

    Space(const Model& m, const FitOptions& o) : model(m) {
        setup.transform = {o.loss};
        setup.robust = {o.robust, o.robust_scale};
        for (const Model::Term& t : m.terms())
            setup.terms.push_back({static_cast<int>(t.type - lobe_types().data()), t.offset, t.type->params.size()});
        for (std::size_t i = 0; i < m.size(); ++i) {
            const ParamSpec& s = m.spec(i);
            const bool log = s.kind == ParamKind::LogScale;
            setup.log_scale.push_back(log);
            lo.push_back(log ? std::log(s.lo) : s.lo);
            hi.push_back(log ? std::log(s.hi) : s.hi);
        }
    }
    std::vector<double> to_solver(const std::vector<double>& p) const {
        std::vector<double> u(p.size());
        for (std::size_t i = 0; i < p.size(); ++i)
            u[i] = std::clamp(setup.log_scale[i] ? std::log(p[i]) : p[i], lo[i], hi[i]);
        return u;
    }
    std::vector<double> to_model(const std::vector<double>& u) const {
        std::vector<double> p(u.size());
        for (std::size_t i = 0; i < u.size(); ++i) {
            const ParamSpec& s = model.spec(i);
            // A variable on its bound maps to the bound exactly (exp(ln lo) may differ in the last bit).
            p[i] = u[i] <= lo[i] ? s.lo : u[i] >= hi[i] ? s.hi : std::clamp(setup.log_scale[i] ? std::exp(u[i]) : u[i], s.lo, s.hi);
        }
        return p;
    }
};

// f·cosθi of the model at every sample, per channel.
std::vector<std::array<double, 3>> model_values(const Space& space, const Samples& s, const std::vector<double>& p) {
    std::vector<std::array<double, 3>> out(s.geometry.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
        double f[3] = {0.0, 0.0, 0.0};
        for (const Term& t : space.setup.terms) {
            double v[3];
            lobe_types()[t.type].eval(s.geometry[k], p.data() + t.offset, v);
            for (int c = 0; c < 3; ++c) f[c] += v[c];
        }
        for (int c = 0; c < 3; ++c) out[k][c] = f[c] * s.cos_i[k];
    }
    return out;
}

// Scales each channel's colour weights so the model matches the data in the least-squares sense of
// f·cosθi: a start then only has to find shapes, not brightness. values: data f·cosθi.
void scale_weights(const Space& space, const Samples& s, const std::vector<std::array<double, 3>>& values,
                   std::vector<double>& p) {
    const auto m = model_values(space, s, p);
    double num[3] = {}, den[3] = {};
    for (std::size_t k = 0; k < m.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            num[c] += values[k][c] * m[k][c];
            den[c] += m[k][c] * m[k][c];
        }
    for (std::size_t i = 0; i < p.size(); ++i) {
        const ParamSpec& spec = space.model.spec(i);
        const int c = channel_of(spec.name);
        if (spec.kind != ParamKind::Weight || c < 0 || !(den[c] > 0.0)) continue;
        p[i] = std::clamp(p[i] * std::fmax(num[c] / den[c], 0.0), spec.lo, spec.hi);
    }
}

struct SolveResult {
    std::vector<double> u;
    ceres::Solver::Summary summary;
};

// After each solver iteration: progress (when given) and the caller's stop check (control.h). What
// either throws must not unwind through Ceres: it ends the solve, and solve() rethrows it.
class IterationHook final : public ceres::IterationCallback {
public:
    explicit IterationHook(std::function<void(int)> on_iteration = nullptr) : on_iteration_(std::move(on_iteration)) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
        try {
            if (on_iteration_) on_iteration_(s.iteration);
            poll_stop();
            return ceres::SOLVER_CONTINUE;
        } catch (...) {
            error_ = std::current_exception();
            return ceres::SOLVER_ABORT;
        }
    }
    void rethrow() const {
        if (error_) std::rethrow_exception(error_);
    }

private:
    std::function<void(int)> on_iteration_;
    std::exception_ptr error_;
};

SolveResult solve(const Space& space, const Samples& samples, std::vector<double> u, int threads, int max_iterations,
                  double seconds, IterationHook& hook) {
    ceres::Problem problem;  // owns the cost functions
    std::vector<double*> blocks;
    for (const Term& t : space.setup.terms) blocks.push_back(u.data() + t.offset);
    const std::size_t n = samples.geometry.size();
    for (std::size_t begin = 0; begin < n; begin += ChunkCost::kChunk)
        problem.AddResidualBlock(new ChunkCost(space.setup, samples, begin, std::min(n, begin + ChunkCost::kChunk)),
                                 nullptr, blocks);
    for (std::size_t t = 0; t < blocks.size(); ++t)
        for (std::size_t j = 0; j < space.setup.terms[t].size; ++j) {
            const std::size_t i = space.setup.terms[t].offset + j;
            problem.SetParameterLowerBound(blocks[t], static_cast<int>(j), space.lo[i]);
            problem.SetParameterUpperBound(blocks[t], static_cast<int>(j), space.hi[i]);
        }
    ceres::Solver::Options o;
    o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    o.linear_solver_type = ceres::DENSE_QR;
    o.max_num_iterations = max_iterations;
    o.max_solver_time_in_seconds = std::max(seconds, 1e-3);
    o.num_threads = threads;
    o.function_tolerance = 1e-9;
    // Bounds are enforced by projecting each step onto the box; Ceres' extra projected line search
    // costs a Jacobian per trial step and, for these problems, does not pay for itself.
    o.max_num_line_search_step_size_iterations = 0;
    o.logging_type = ceres::SILENT;
    o.callbacks.push_back(&hook);
    SolveResult r;
    ceres::Solve(o, &problem, &r.summary);
    hook.rethrow();
    r.u = std::move(u);
    return r;
}

// Samples inside the cut-off with finite values, in solver form.
struct Prepared {
    Samples samples;
    std::vector<std::array<double, 3>> values;  // data f·cosθi
    std::size_t cutoff = 0, invalid = 0, negative = 0;
    bool any_positive = false;
};

Prepared prepare(const MeasurementSet& data, const FitOptions& options) {
    const double min_cos = std::fmax(std::cos(options.max_theta_deg * std::numbers::pi / 180.0), 0.0);
    const Transform transform{options.loss};
    Prepared out;
    for (const Measurement& m : data.samples) {
        if (!(std::isfinite(m.f[0]) && std::isfinite(m.f[1]) && std::isfinite(m.f[2]) && std::isfinite(m.wi.x + m.wi.y) &&
              std::isfinite(m.wo.x + m.wo.y))) {
            ++out.invalid;
            continue;
        }
        if (!(m.wi.z > min_cos && m.wo.z > min_cos)) {
            ++out.cutoff;
            continue;
        }
        const Vec3 wi = normalize(m.wi), wo = normalize(m.wo);
        out.samples.geometry.push_back(make_geometry(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z));
        out.samples.cos_i.push_back(wi.z);
        std::array<double, 3> v, t;
        for (int c = 0; c < 3; ++c) {
            v[c] = m.f[c] * wi.z;
            t[c] = transform.value(v[c]);
            out.negative += m.f[c] < 0.0;
            out.any_positive = out.any_positive || m.f[c] > 0.0;
        }
        out.values.push_back(v);
        out.samples.target.push_back(t);
    }
    return out;
}

// A fixed pseudo-random subset of about n samples (all of them if there are few).
Samples subset(const Prepared& all, std::size_t n, std::uint64_t seed, std::vector<std::array<double, 3>>& values) {
    const std::size_t total = all.samples.geometry.size();
    const double keep = n >= total ? 1.0 : static_cast<double>(n) / static_cast<double>(total);
    Samples s;
    for (std::size_t k = 0; k < total; ++k) {
        if (keep < 1.0 && detail::unit_hash(k, seed ^ 0x5eed) >= keep) continue;
        s.geometry.push_back(all.samples.geometry[k]);
        s.cos_i.push_back(all.samples.cos_i[k]);
        s.target.push_back(all.samples.target[k]);
        values.push_back(all.values[k]);
    }
    return s;
}

bool usable(const ceres::Solver::Summary& s) { return s.IsSolutionUsable() && std::isfinite(s.final_cost); }

FitResult fit_samples(const MeasurementSet& data, const std::string& model_text, const FitOptions& options,
                      Clock::time_point t0) {
    if (!(options.max_theta_deg > 0.0 && options.max_theta_deg <= 90.0))
        throw ValueError("fit: max_theta_deg must be in (0, 90]");
    if (options.starts < 1 || options.starts > FitOptions::kMaxStarts)
        throw ValueError("fit: starts=" + std::to_string(options.starts) + " is outside [1, " +
                         std::to_string(FitOptions::kMaxStarts) + "]");
    if (options.max_iterations < 1 || options.start_iterations < 1)
        throw ValueError("fit: max_iterations and start_iterations must be at least 1");
    if (!(options.robust_scale > 0.0)) throw ValueError("fit: robust_scale must be positive");
    if (!(options.max_seconds > 0.0)) throw ValueError("fit: max_seconds must be positive");
    const Model model = Model::parse(model_text);
    std::vector<double> first = options.initial.empty() ? model.defaults() : options.initial;
    model.validate(first);
    const Space space(model, options);
    const Clock::time_point deadline = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.max_seconds));
    auto remaining = [&] { return std::chrono::duration<double>(deadline - Clock::now()).count(); };

    std::mutex progress_mutex;
    auto progress = [&](double fraction) {
        if (!options.progress) return;
        std::lock_guard lock(progress_mutex);
        options.progress(std::clamp(fraction, 0.0, 1.0));
    };

    FitReport rep;
    rep.model = model.text();
    rep.loss = options.loss;
    rep.starts = options.starts;
    const Prepared all = prepare(data, options);
    rep.samples = all.samples.geometry.size();
    rep.excluded_cutoff = all.cutoff;
    rep.excluded_invalid = all.invalid;
    if (all.negative)
        rep.warnings.push_back(std::to_string(all.negative) + " negative channel values (measurement noise)" +
                               (options.loss == FitLoss::Log ? ", taken as 0 by the log loss" : ""));

    auto finish = [&](std::vector<double> params) {
        rep.seconds = seconds_since(t0);
        progress(1.0);
        return FitResult{AnalyticBrdf(model, std::move(params)), std::move(rep)};
    };
    const std::size_t needed = std::max<std::size_t>(2 * model.size(), 10);
    if (rep.samples < needed || !all.any_positive) {
        rep.status = FitStatus::InsufficientData;
        if (rep.samples < needed)
            rep.message = std::to_string(rep.samples) + " usable samples (of " + std::to_string(data.samples.size()) +
                          "; " + std::to_string(all.cutoff) + " outside the " + std::to_string(options.max_theta_deg) +
                          " degree cut-off, " + std::to_string(all.invalid) + " without a finite value); model " +
                          model.text() + " needs at least " + std::to_string(needed);
        else
            rep.message = "every sample is zero or negative: there is no reflectance to fit";
        rep.message += "; the model's defaults are returned";
        return finish(first);
    }

    // Phase 1: every start on a fixed subset.
    std::vector<std::array<double, 3>> coarse_values;
    const Samples coarse = subset(all, options.coarse_samples, options.seed, coarse_values);
    std::vector<std::vector<double>> starts(options.starts);
    detail::Random random(options.seed);
    for (int k = 0; k < options.starts; ++k) {
        std::vector<double> p = first;
        if (k > 0)
            for (std::size_t i = 0; i < p.size(); ++i) {
                const ParamSpec& s = model.spec(i);
                const double u = random.uniform();
                p[i] = s.kind == ParamKind::LogScale ? s.lo * std::pow(s.hi / s.lo, u) : s.lo + (s.hi - s.lo) * u;
            }
        scale_weights(space, coarse, coarse_values, p);
        starts[k] = space.to_solver(p);
    }
    std::vector<SolveResult> results(options.starts);
    detail::parallel_for(
        options.starts, options.threads,
        [&](int, int k) {
            IterationHook hook;
            results[k] = solve(space, coarse, starts[k], 1, options.start_iterations, remaining(), hook);
        },
        [&](int done, int n) { progress(0.6 * done / n); });
    int best = -1;
    for (int k = 0; k < options.starts; ++k) {
        const ceres::Solver::Summary& s = results[k].summary;
        rep.start_costs.push_back(usable(s) ? s.final_cost : std::numeric_limits<double>::quiet_NaN());
        rep.total_iterations += static_cast<int>(s.iterations.size());
        if (usable(s) && (best < 0 || s.final_cost < results[best].summary.final_cost)) best = k;
    }
    if (best < 0) {
        rep.status = FitStatus::NoConvergence;
        rep.message = "the solver failed from every start (" + results[0].summary.message + "); the first start is returned";
        rep.termination = ceres::TerminationTypeToString(results[0].summary.termination_type);
        return finish(space.to_model(starts[0]));
    }
    rep.best_start = best;

    // Phase 2: the best start refined on every sample.
    SolveResult final_result = std::move(results[best]);
    rep.iterations = static_cast<int>(final_result.summary.iterations.size());
    {
        IterationHook hook([&](int iteration) { progress(0.6 + 0.4 * iteration / options.max_iterations); });
        // Ceres takes at most the hardware's threads, and says so on stderr (through glog) when given
        // more: the library prints nothing.
        SolveResult refined = solve(space, all.samples, final_result.u,
                                    std::min(resolve_threads(options.threads), resolve_threads(0)),
                                    options.max_iterations, remaining(), hook);
        rep.total_iterations += static_cast<int>(refined.summary.iterations.size());
        rep.iterations += static_cast<int>(refined.summary.iterations.size());
        if (usable(refined.summary)) final_result = std::move(refined);
        else rep.warnings.push_back("refinement on all samples failed (" + refined.summary.message + "); the subset fit is kept");
    }
    const ceres::Solver::Summary& summary = final_result.summary;
    rep.termination = ceres::TerminationTypeToString(summary.termination_type);
    rep.initial_cost = summary.initial_cost;
    rep.final_cost = summary.final_cost;
    std::vector<double> params = space.to_model(final_result.u);

    // Cost per channel at the solution, over all samples, and the share of the data's variation left.
    const auto m = model_values(space, all.samples, params);
    double mean[3] = {};
    for (const auto& t : all.samples.target)
        for (int c = 0; c < 3; ++c) mean[c] += t[c] / static_cast<double>(m.size());
    double residual_sq = 0, total_sq = 0;
    for (std::size_t k = 0; k < m.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            const double t = all.samples.target[k][c], d = space.setup.transform.value(m[k][c]) - t;
            const double r = space.setup.robust.apply(d)[0];
            rep.channel_cost[c] += 0.5 * r * r;
            residual_sq += d * d;
            total_sq += (t - mean[c]) * (t - mean[c]);
        }
    rep.unexplained = total_sq > 0.0 ? residual_sq / total_sq : 0.0;
    if (rep.unexplained > FitReport::kPoorFitUnexplained) {
        rep.poor_fit = true;
        char buf[200];
        std::snprintf(buf, sizeof buf, "poor fit: the model leaves %.0f%% of the data's variation (in the %s loss) unexplained",
                      100.0 * rep.unexplained, fit_loss_name(options.loss));
        rep.warnings.push_back(buf);
    }

    // Active bounds, except a colour weight at 0 (that lobe is simply absent in that channel) and
    // the shape of a lobe that is absent in every channel.
    for (const Model::Term& t : model.terms()) {
        const bool absent = t.type->linear_weights && params[t.offset] == 0.0 && params[t.offset + 1] == 0.0 &&
                            params[t.offset + 2] == 0.0;
        if (absent) {
            rep.warnings.push_back("lobe " + t.label + " has weight 0 in every channel: it is unused");
            continue;
        }
        for (std::size_t i = t.offset; i < t.offset + t.type->params.size(); ++i) {
            const double tol = 1e-4 * (space.hi[i] - space.lo[i]);
            const bool at_lo = final_result.u[i] <= space.lo[i] + tol, at_hi = final_result.u[i] >= space.hi[i] - tol;
            if (at_hi || (at_lo && model.spec(i).kind != ParamKind::Weight)) rep.at_bounds.push_back(model.name(i));
        }
    }
    if (summary.termination_type != ceres::CONVERGENCE) {
        rep.status = FitStatus::NoConvergence;
        rep.message = "stopped without meeting the convergence tolerances: " + summary.message;
    } else if (!rep.at_bounds.empty()) {
        rep.status = FitStatus::HitBounds;
        rep.message = "converged with parameters on their bounds:";
        for (const std::string& name : rep.at_bounds) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "=%.4g", params[model.find(name)]);
            rep.message += " " + name + buf;
        }
    } else {
        rep.status = FitStatus::Converged;
        rep.message = summary.message;
    }
    return finish(std::move(params));
}

// The second poor-fit test, once the metrics are known.
void check_energy(FitReport& rep) {
    if (!rep.metrics || !(rep.metrics->cos_rmse_rel.mean > FitReport::kPoorFitCosRmseRel)) return;
    rep.poor_fit = true;
    char buf[200];
    std::snprintf(buf, sizeof buf, "poor fit: cos_rmse_rel %.2f against the input (the model misses the data's reflected energy)",
                  rep.metrics->cos_rmse_rel.mean);
    rep.warnings.push_back(buf);
}

}  // namespace

FitResult fit(const MeasurementSet& data, const std::string& model, const FitOptions& options) {
    const Clock::time_point t0 = Clock::now();
    FitResult r = fit_samples(data, model, options, t0);
    if (r.report.status != FitStatus::InsufficientData) {
        MetricOptions mo = options.metrics;
        mo.max_theta_deg = options.max_theta_deg;
        r.report.metrics = compare(data, r.model, mo);
        check_energy(r.report);
    }
    r.report.seconds = seconds_since(t0);
    return r;
}

FitResult fit(const Brdf& source, const std::string& model, const FitOptions& options) {
    const Clock::time_point t0 = Clock::now();
    SampleOptions so = options.sampling;
    so.max_theta_deg = options.max_theta_deg;
    so.threads = options.threads;
    const GridSamples samples = sample_brdf(source, so);
    FitResult r = fit_samples(samples.set, model, options, t0);
    r.report.excluded_invalid += samples.invalid;
    r.report.grid_bins = samples.eligible;
    if (r.report.status != FitStatus::InsufficientData) {
        MetricOptions mo = options.metrics;
        mo.max_theta_deg = options.max_theta_deg;
        mo.threads = options.threads;
        r.report.metrics = compare(source, r.model, mo);
        check_energy(r.report);
    }
    r.report.seconds = seconds_since(t0);
    return r;
}

}  // namespace brdfz
