// brdfz fit IN --model MODEL [--loss log|cos|cbrt] [--starts 8] -o OUT
// Fits an analytic model (a sum of lobes) to any BRDF file or scattered measurements (Cornell, ALTA),
// prints the fit report and writes the model: OUT.json (docs/model-json.md, with the fit's provenance)
// or OUT.brdfz store it as parameters; table formats (.binary, .exr) tabulate it. Exit status: 0 when the fit converged (possibly with
// parameters on their bounds, or poor: the status line says "but poor fit" and a warning why), 1 when
// it did not (no_convergence: the best parameters are still written; insufficient_data: nothing is
// written), with one line on stderr saying which.
#include <cstdio>
#include <iostream>

#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"
#include "brdfz/formats/model_json.h"
#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {
namespace {

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

void print_report(const std::string& in, const FitResult& r, RobustLoss robust, const std::string& out, bool json,
                  std::ostream& os) {
    const FitReport& p = r.report;
    const Model& m = r.model.model();
    if (json) {
        JsonWriter j(os);
        j.begin_object();
        j.key("input").value(in);
        j.key("output").value(out);
        j.key("model").value(p.model);
        j.key("loss").value(std::string(fit_loss_name(p.loss)));
        j.key("robust").value(std::string(robust_loss_name(robust)));
        j.key("status").value(std::string(fit_status_name(p.status)));
        j.key("message").value(p.message);
        j.key("poor_fit").value(p.poor_fit);
        j.key("warnings").begin_array();
        for (const std::string& w : p.warnings) j.value(w);
        j.end_array();
        j.key("at_bounds").begin_array();
        for (const std::string& a : p.at_bounds) j.value(a);
        j.end_array();
        j.key("parameters").begin_object();
        for (std::size_t i = 0; i < m.size(); ++i) j.key(m.name(i)).value(r.model.params()[i]);
        j.end_object();
        j.key("samples").value(p.samples);
        j.key("excluded_cutoff").value(p.excluded_cutoff);
        j.key("excluded_invalid").value(p.excluded_invalid);
        j.key("grid_bins").value(p.grid_bins);
        j.key("channel_cost").begin_array();
        for (double c : p.channel_cost) j.value(c);
        j.end_array();
        j.key("initial_cost").value(p.initial_cost);
        j.key("final_cost").value(p.final_cost);
        j.key("unexplained").value(p.unexplained);
        j.key("iterations").value(static_cast<std::size_t>(p.iterations));
        j.key("total_iterations").value(static_cast<std::size_t>(p.total_iterations));
        j.key("termination").value(p.termination);
        j.key("starts").value(static_cast<std::size_t>(p.starts));
        j.key("best_start").value(static_cast<double>(p.best_start));
        j.key("start_costs").begin_array();
        for (double c : p.start_costs) j.value(c);
        j.end_array();
        j.key("seconds").value(p.seconds);
        if (p.metrics) {
            j.key("metrics");
            write_metrics(j, *p.metrics);
        }
        j.end_object();
        os << "\n";
        return;
    }
    os << "fit " << in << " with " << p.model << " (" << fit_loss_name(p.loss) << " loss"
       << (robust == RobustLoss::None ? "" : std::string(", ") + robust_loss_name(robust) + " robust loss") << ")\n"
       << "  status       " << fit_status_name(p.status) << (p.poor_fit ? " but poor fit (see the warnings)" : "")
       << ": " << p.message << "\n"
       << "  samples      " << p.samples << " used, " << p.excluded_cutoff << " outside the cut-off, "
       << p.excluded_invalid << " without a finite value";
    if (p.grid_bins) os << " (drawn from " << p.grid_bins << " grid bins inside the cut-off)";
    os << "\n"
       << "  starts       " << p.starts << ", "
       << (p.best_start < 0 ? std::string("none usable") : "best #" + std::to_string(p.best_start)) << ", subset costs";
    for (double c : p.start_costs) os << " " << fmt("%.4g", c);
    os << "\n  iterations   " << p.iterations << " for the kept start (" << p.total_iterations << " in all), "
       << (p.termination.empty() ? "no solve" : p.termination) << "\n"
       << "  cost         " << fmt("%.6g", p.initial_cost) << " -> " << fmt("%.6g", p.final_cost) << "; per channel "
       << fmt("%.4g", p.channel_cost[0]) << " " << fmt("%.4g", p.channel_cost[1]) << " " << fmt("%.4g", p.channel_cost[2])
       << "\n  unexplained  " << fmt("%.2f", 100.0 * p.unexplained) << "% of the data's variation (in the loss)\n"
       << "  time         " << fmt("%.3f", p.seconds) << " s\n"
       << "  parameters\n";
    for (std::size_t i = 0; i < m.size(); ++i) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "    %-22s %-12.6g [%g, %g]\n", m.name(i).c_str(), r.model.params()[i], m.spec(i).lo,
                      m.spec(i).hi);
        os << buf;
    }
    if (p.metrics) {
        os << "  against the input\n";
        print_metrics(*p.metrics, false, os);
    }
    for (const std::string& w : p.warnings) os << "  warning: " << w << "\n";
    os << (out.empty() ? "  nothing written\n" : "  wrote " + out + "\n");
}

}  // namespace

void add_fit(CLI::App& app) {
    struct Args {
        std::string in, out, model, loss = "log", robust = "none";
        bool json = false;
        LoadOptions load;
        FitOptions fit;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("fit", "fit an analytic model (e.g. lambert+ggx) to a BRDF or measurements; "
                                              "exit 1 when the fit did not converge");
    cmd->add_option("IN", args->in, "BRDF file or measurements (.brdf, .dat)")->required();
    cmd->add_option("--model", args->model, "lobes joined by '+': " + lobe_family_names())->required();
    cmd->add_option("-o,--out", args->out, "output: .json or .brdfz keep the model, .binary/.exr tabulate it")->required();
    cmd->add_option("--loss", args->loss, "cos (cosine-weighted L2), log (ln(1+f cos)) or cbrt")->capture_default_str();
    cmd->add_option("--starts", args->fit.starts, "seeded starts; the best is refined")
        ->capture_default_str()
        ->check(CLI::Range(1, FitOptions::kMaxStarts));
    cmd->add_option("--seed", args->fit.seed, "seed of the starts and the sample subset")
        ->capture_default_str()
        ->check(unsigned_integer());
    cmd->add_option("--robust", args->robust, "robust loss: none, huber or cauchy")->capture_default_str();
    cmd->add_option("--robust-scale", args->fit.robust_scale, "residual where the robust loss bends")->capture_default_str();
    cmd->add_option("--max-theta", args->fit.max_theta_deg, "leave out theta_i or theta_o at or above (degrees)")
        ->capture_default_str();
    cmd->add_option("--samples", args->fit.sampling.max_samples, "grid bins sampled from a BRDF (0: all)")
        ->capture_default_str();
    add_threads_option(cmd, args->fit.threads);
    cmd->add_option("--max-seconds", args->fit.max_seconds, "wall-clock bound of the fit")->capture_default_str();
    cmd->add_flag("--json", args->json, "print the report as JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        FitOptions o = args->fit;
        o.loss = parse_fit_loss(args->loss);
        o.robust = parse_robust_loss(args->robust);
        o.progress = progress_bar("fitting");
        // Check the model string and the output's format before spending time on loading and fitting.
        Model::parse(args->model);
        const std::string out_format = format_of(args->out, Access::Write);
        check_output(args->out);
        FitResult r = [&] {
            if (holds_measurements(args->in)) return fit(load_measurements(args->in).set, args->model, o);
            const Loaded in = load(args->in, args->load);
            return fit(*in.brdf, args->model, o);
        }();
        const FitReport& p = r.report;
        std::string written;
        if (p.status != FitStatus::InsufficientData) {
            if (out_format == "json") {
                model_json::Provenance prov = {{"source", args->in},
                                               {"status", std::string(fit_status_name(p.status))},
                                               {"loss", std::string(fit_loss_name(p.loss))},
                                               {"robust", std::string(robust_loss_name(o.robust))},
                                               {"samples", static_cast<double>(p.samples)},
                                               {"final_cost", p.final_cost},
                                               {"unexplained", p.unexplained}};
                if (p.metrics) prov.push_back({"cos_rmse_rel", p.metrics->cos_rmse_rel.mean});
                model_json::write(args->out, r.model, prov);
            } else {
                SaveOptions so;
                so.source = args->in;
                so.threads = o.threads;
                save(r.model, args->out, so);
            }
            written = args->out;
        }
        print_report(args->in, r, o.robust, written, args->json, std::cout);
        if (p.status == FitStatus::InsufficientData)
            throw Error(args->in + ": insufficient data to fit " + p.model + "; nothing written");
        if (p.status == FitStatus::NoConvergence)
            throw Error(args->in + ": the fit did not converge; its best parameters were written to " + args->out);
    });
}

}  // namespace brdfz::cli
