// brdfz diff A B [--json] [--over grid|directions]: error metrics of B against the reference A (a BRDF,
// or Cornell / ALTA measurements), over A's grid or over direction pairs (metrics.h).
#include <iostream>

#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {

void add_diff(CLI::App& app) {
    struct Args {
        std::string a, b;
        bool json = false;
        LoadOptions load;
        MetricOptions metrics;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("diff", "error metrics of B against the reference A");
    cmd->add_option("A", args->a, "reference")->required();
    cmd->add_option("B", args->b, "approximation")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->add_option("--max-theta", args->metrics.max_theta_deg, "leave out theta_i or theta_o at or above (degrees)")
        ->capture_default_str();
    add_over_options(cmd, args->metrics);
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        // A may be scattered measurements (Cornell, ALTA): B is then judged at the measured points.
        // A is loaded first, so that its errors are the ones reported.
        Metrics m;
        if (holds_measurements(args->a)) {
            const LoadedMeasurements a = load_measurements(args->a);
            m = compare(a.set, *load(args->b, args->load).brdf, args->metrics);
        } else {
            const Loaded a = load(args->a, args->load);
            m = compare(*a.brdf, *load(args->b, args->load).brdf, args->metrics);
        }
        if (!args->json) std::cout << args->b << " against " << args->a << "\n";
        print_metrics(m, args->json, std::cout, args->metrics.over);
    });
}

}  // namespace brdfz::cli
