// brdfz compress IN -o OUT --repr SPEC
// brdfz compress IN -o OUT --auto [--max-error E] [--max-bytes B] [--metric log|cos|image]
//                                  [--scene SCENE.json] [--over grid|directions]
// Builds a compact representation (compress.h) of any BRDF file, or fits scattered measurements
// (analytic only), writes it (.brdfz keeps the representation itself; table formats tabulate it) and
// reports what it achieved: bytes, ratio to the input file, the metrics against the input, batch
// eval speed and build time. --auto tries candidates from cheapest to richest (select.h) and keeps the
// smallest that meets the error budget, the most accurate within the size budget, or the smallest
// within both, reporting every candidate; exit status 2, nothing written, when none does. --auto
// judges over direction pairs unless --over grid: the grid's bins weigh pairs unlike a renderer, and
// rank settings that render off-colour ahead of better ones.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "brdfz/errors.h"
#include "brdfz/formats/scene_json.h"
#include "brdfz/select.h"
#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {
namespace {

struct Outcome {
    std::string in, out;
    std::uintmax_t input_bytes = 0;
    const Trial* trial = nullptr;
    Over over = Over::Grid;
};

double ratio_of(const Outcome& o) {
    return o.trial->bytes ? static_cast<double>(o.input_bytes) / static_cast<double>(o.trial->bytes) : 0.0;
}

void write_trial_keys(JsonWriter& j, const Outcome& o) {
    const Trial& t = *o.trial;
    j.key("input").value(o.in).key("output").value(o.out);
    j.key("repr").value(t.spec).key("describe").value(t.describe);
    j.key("input_bytes").value(static_cast<std::size_t>(o.input_bytes));
    j.key("bytes").value(t.bytes).key("ratio").value(ratio_of(o));
    j.key("build_seconds").value(t.build_seconds);
    j.key("eval_pairs_per_second").value(t.eval_rate);
    j.key("notes").begin_array();
    for (const std::string& n : t.notes) j.value(n);
    j.end_array();
    j.key("metrics");
    write_metrics(j, t.metrics);
}

void print_trial(const Outcome& o, std::ostream& os) {
    const Trial& t = *o.trial;
    char line[256];
    os << "compressed " << o.in << " with " << t.spec << "\n  stores       " << t.describe << "\n";
    std::snprintf(line, sizeof line, "  bytes        %zu (input file %ju bytes: %.1fx smaller)\n", t.bytes, o.input_bytes,
                  ratio_of(o));
    os << line;
    std::snprintf(line, sizeof line, "  build time   %.3f s\n  eval speed   %.3g pairs/s (batch, one thread)\n",
                  t.build_seconds, t.eval_rate);
    os << line << "  against the input\n";
    print_metrics(t.metrics, false, os, o.over);
    for (const std::string& n : t.notes) os << "  note: " << n << "\n";
    os << "  wrote " << o.out << "\n";
}

void print_candidate(const Candidate& c, std::ostream& os) {
    char line[512];
    std::snprintf(line, sizeof line, "  %-34s %10zu B  error %-10.4g %9.3g pairs/s %7.2f s  %s\n", c.trial.spec.c_str(),
                  c.trial.bytes, c.error, c.trial.eval_rate, c.trial.build_seconds, c.reason.c_str());
    os << line;
}

void write_candidates(JsonWriter& j, const Selection& s) {
    j.key("candidates").begin_array();
    for (const Candidate& c : s.tried) {
        j.begin_object();
        j.key("repr").value(c.trial.spec).key("bytes").value(c.trial.bytes).key("error").value(c.error);
        j.key("eval_pairs_per_second").value(c.trial.eval_rate).key("build_seconds").value(c.trial.build_seconds);
        j.key("accepted").value(c.accepted).key("reason").value(c.reason);
        j.end_object();
    }
    j.end_array();
}

}  // namespace

void add_compress(CLI::App& app) {
    struct Args {
        std::string in, out, repr, metric = "log", scene;
        std::vector<std::string> candidates;
        bool json = false, automatic = false;
        double max_error = 0;
        std::uint64_t max_bytes = 0;
        int threads = 0;
        LoadOptions load;
        MetricOptions metrics;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("compress", "build a compact representation and report bytes, error and speed");
    cmd->add_option("IN", args->in, "BRDF file, or measurements (.brdf, .dat: analytic only)")->required();
    cmd->add_option("-o,--out", args->out, "output: .brdfz keeps the representation; table formats tabulate it")
        ->required();
    CLI::Option* repr = cmd->add_option("--repr", args->repr, "representation spec KIND[:KEY=VALUE,...]; kinds: " + [] {
        std::string kinds;
        for (const std::string& k : compress_kinds()) kinds += (kinds.empty() ? "" : ", ") + k;
        return kinds + " (keys and defaults: docs/repr-specs.md)";
    }());
    CLI::Option* automatic =
        cmd->add_flag("--auto", args->automatic, "choose a candidate by budget: the smallest that meets --max-error, the "
                                                  "most accurate within --max-bytes, or the smallest within both")
            ->excludes(repr);
    CLI::Option* max_error =
        cmd->add_option("--max-error", args->max_error, "error budget of --auto (unitless, in --metric)")->needs(automatic);
    CLI::Option* max_bytes =
        cmd->add_option("--max-bytes", args->max_bytes, "size budget of --auto: the representation's bytes at most")
            // Checked as text: the conversion to an unsigned count would wrap a negative one.
            ->check(CLI::Validator(
                [](std::string& text) {
                    const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
                    return digits && text.find_first_not_of('0') != std::string::npos
                               ? std::string()
                               : "must be a whole number of bytes >= 1, not " + text;
                },
                "BYTES"))
            ->needs(automatic);
    cmd->add_option("--metric", args->metric, "error of --auto: log (log_rmse), cos (cos_rmse_rel) or image "
                                              "(relative pixel RMSE)")
        ->capture_default_str()
        ->needs(automatic);
    cmd->add_option("--scene", args->scene, "scene file (docs/scene-json.md): measure the error where it looks")
        ->needs(automatic);
    char threshold[16];
    std::snprintf(threshold, sizeof threshold, "%g", kReciprocityThreshold);
    cmd->add_option("--candidate", args->candidates,
                    "a candidate spec for --auto (repeatable; default: cheapest to richest of every kind, phi_d kept "
                    "whole with symmetry=bilateral when IN's reciprocity error, as `brdfz info` prints it, is above " +
                        std::string(threshold) + ")")
        ->needs(automatic);
    CLI::Option* over = add_over_options(cmd, args->metrics)->default_str("grid; directions with --auto");
    add_threads_option(cmd, args->threads);
    cmd->add_flag("--json", args->json, "print the report as JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args, max_error, max_bytes, over] {
        if (!args->automatic && args->repr.empty())
            throw ValueError("compress: give --repr SPEC or --auto with --max-error E, --max-bytes B or both");
        if (args->automatic && !*max_error && !*max_bytes)
            throw ValueError("compress --auto: give --max-error E, --max-bytes B or both");
        if (*max_error && !(args->max_error > 0.0 && std::isfinite(args->max_error)))
            throw ValueError("compress --auto: --max-error must be a finite number > 0");
        // Check what can be checked before spending time on loading and building.
        if (!args->automatic) check_spec(args->repr);
        if (args->automatic && !*over) args->metrics.over = Over::Directions;
        for (const std::string& c : args->candidates) check_spec(c);
        format_of(args->out, Access::Write);
        check_output(args->out);
        const auto budget = [&] {
            std::ostringstream text;
            if (*max_error) text << "error at most " << args->max_error;
            if (*max_bytes) text << (*max_error ? ", " : "") << "at most " << args->max_bytes << " bytes";
            return text.str();
        };
        SelectOptions select;
        if (args->automatic) {
            select.max_error = *max_error ? std::optional<double>(args->max_error) : std::nullopt;
            if (*max_bytes) select.max_bytes = args->max_bytes;
            select.metric = parse_scene_metric(args->metric);
            select.candidates = args->candidates;
            if (!args->scene.empty()) select.scene = scene_json::load(args->scene);
        }
        TrialOptions options;
        options.compress = with_file_access(options.compress);
        options.compress.threads = args->threads;
        options.metrics = args->metrics;
        options.metrics.threads = args->threads;
        Outcome o;
        o.in = args->in;
        o.over = args->metrics.over;
        o.input_bytes = std::filesystem::file_size(args->in);
        SaveOptions save_options;
        save_options.source = args->in;

        // The container records errors over the grid (formats/SPEC.md, /achieved), whatever --over says.
        const auto record_grid_metrics = [&](const Brdf& source, const Trial& t) {
            if (options.metrics.over == Over::Grid) return;
            MetricOptions grid = options.metrics;
            grid.over = Over::Grid;
            save_options.source_metrics = compare(source, *t.brdf, grid);
        };
        Trial single;
        Selection selection;
        if (holds_measurements(args->in)) {
            if (args->automatic) throw ValueError("compress --auto needs a BRDF on a grid; scattered measurements can only be fitted (--repr analytic:MODEL)");
            const LoadedMeasurements in = load_measurements(args->in);
            options.compress.progress = progress_bar("compressing");
            single = trial(in.set, args->repr, options);
            save_options.source_format = in.info.format;
        } else {
            const Loaded in = load(args->in, args->load);
            save_options.source_format = in.info.format;
            if (args->automatic) {
                select.trial = options;
                if (!args->json)
                    std::cout << "trying candidates for " << args->in << " (" << budget() << ", error in " << args->metric
                              << (args->scene.empty() ? "" : " under " + args->scene) << " over "
                              << over_name(args->metrics.over) << ")\n";
                select.on_candidate = [&](const Candidate& c) {
                    if (!args->json) print_candidate(c, std::cout), std::cout.flush();
                };
                selection = select_representation(*in.brdf, select);
                if (selection.best()) record_grid_metrics(*in.brdf, selection.best()->trial);
            } else {
                options.compress.progress = progress_bar("compressing");
                single = trial(*in.brdf, args->repr, options);
                record_grid_metrics(*in.brdf, single);
            }
        }
        if (args->automatic && !selection.best()) {
            if (args->json) {
                JsonWriter j(std::cout);
                j.begin_object().key("input").value(o.in).key("chosen").value(std::string());
                write_candidates(j, selection);
                j.end_object();
                std::cout << "\n";
            }
            std::cout.flush();
            std::cerr << "brdfz: " << args->in << ": no candidate meets the budget (" << budget() << "); nothing written\n";
            throw CLI::RuntimeError(2);
        }
        o.trial = args->automatic ? &selection.best()->trial : &single;
        save_options.build_spec = o.trial->spec;
        if (!save_options.source_metrics) save_options.source_metrics = o.trial->metrics;
        save_options.threads = args->threads;
        save(*o.trial->brdf, args->out, save_options);
        o.out = args->out;
        if (args->json) {
            JsonWriter j(std::cout);
            j.begin_object();
            write_trial_keys(j, o);
            if (args->automatic) {
                j.key("chosen").value(o.trial->spec).key("error").value(selection.best()->error);
                j.key("max_error").value(*max_error ? args->max_error : std::nan(""));
                j.key("max_bytes").value(*max_bytes ? static_cast<double>(args->max_bytes) : std::nan(""));
                j.key("metric").value(args->metric);
                j.key("over").value(std::string(over_name(args->metrics.over)));
                j.key("scene").value(args->scene);
                write_candidates(j, selection);
            }
            j.end_object();
            std::cout << "\n";
        } else {
            if (args->automatic) std::cout << "chose " << o.trial->spec << "\n";
            print_trial(o, std::cout);
        }
    });
}

}  // namespace brdfz::cli
