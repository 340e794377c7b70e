// brdfz demo: the main job on the embedded default material, with no data files.
// A built-in coated-diffuse BRDF is measured by the virtual gonioreflectometer at MERL resolution,
// written as a MERL table, read back (checked bit-identical), reported, and compared with the
// analytic original; then every setting of the compression benchmark is built from the table and
// measured over the grid and over direction pairs (table printed, CSV written for scripts/demo's
// charts: python -m brdfz.bench --from-csv).
// Exit status 1 when a representation could not be built (after the table and the CSV are written).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/merl.h"
#include "brdfz/metrics.h"
#include "brdfz/select.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/tabulate.h"
#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {

void add_demo(CLI::App& app) {
    auto out_dir = std::make_shared<std::string>("brdfz-demo");
    auto specs = std::make_shared<std::vector<std::string>>();
    CLI::App* cmd = app.add_subcommand("demo", "run the pipeline on a built-in material (no data files needed)");
    cmd->add_option("--out", *out_dir, "output folder")->capture_default_str();
    cmd->add_option("--repr", *specs, "a representation to build and measure (repeatable; default: every setting of "
                                      "the compression benchmark)");
    cmd->callback([out_dir, specs] {
        // A misspelt representation is refused before the work starts.
        for (const std::string& spec : *specs) check_spec(spec);
        using clock = std::chrono::steady_clock;
        const CoatedDiffuse material;
        std::cout << "material: " << material.describe() << "\n\n";

        std::cout << "1. virtual gonioreflectometer, MERL resolution 90x90x180\n";
        TabulateOptions t;
        t.progress = progress_bar("   tabulating");
        const auto t0 = clock::now();
        Tabulated tab = tabulate(material, t);
        const double secs = std::chrono::duration<double>(clock::now() - t0).count();
        std::cout << "   " << tab.counts.valid << " valid bins, " << tab.counts.below_horizon
                  << " below the horizon (written as unmeasured), in " << static_cast<int>(secs * 1000.0) << " ms\n\n";

        std::filesystem::create_directories(*out_dir);
        const std::string path = (std::filesystem::path(*out_dir) / "coated-diffuse.binary").string();
        std::cout << "2. MERL round trip\n";
        merl::write(path, tab.table);
        merl::ReadResult back = merl::read(path);
        const bool identical = back.table == tab.table;
        std::cout << "   wrote " << path << " (" << std::filesystem::file_size(path) << " bytes); read back: "
                  << (identical ? "bit-identical" : "DIFFERENT") << "\n\n";
        if (!identical) throw Error(path + ": MERL round trip changed the table");

        std::cout << "3. info\n";
        const Loaded loaded = load(path);
        print_info(path, loaded, false, std::cout);

        std::cout << "\n4. table (linear lookup) against the analytic material, sampled between the table's samples\n";
        print_metrics(compare(material, *loaded.brdf), false, std::cout);

        const std::string csv_path = (std::filesystem::path(*out_dir) / "representations.csv").string();
        std::cout << "\n5. every representation of the table, as `brdfz compress --repr SPEC` measures it over the grid "
                     "and over direction pairs (one thread for eval speed)\n";
        char line[256];
        std::snprintf(line, sizeof line, "   %-34s %10s %10s %12s %10s %12s %12s %8s\n", "setting", "bytes", "ratio",
                      "cos_rmse_rel", "log_rmse", "over dirs", "eval pairs/s", "build s");
        std::cout << line;
        // Over directions too: the charts and the budget-driven selection of scripts/demo judge there.
        MetricOptions over_directions;
        over_directions.over = Over::Directions;
        std::ostringstream csv;  // written whole at the end, so that a killed demo leaves no partial CSV
        csv << kSweepCsvHeader << "," << kSweepCsvDirectionsColumns << "\n";
        const auto input_bytes = std::filesystem::file_size(path);
        const std::vector<std::string> built = specs->empty() ? benchmark_specs() : *specs;
        std::size_t failed = 0;
        for (const std::string& spec : built) {
            std::snprintf(line, sizeof line, "   %-34s ", spec.c_str());
            std::cout << line << std::flush;  // the fits take seconds: show what is being built
            try {
                const Trial r = trial(*loaded.brdf, spec);
                const Metrics d = compare(*loaded.brdf, *r.brdf, over_directions);
                csv << sweep_csv_row("coated-diffuse", "merl", spec, input_bytes, &r) << sweep_csv_directions(&d) << "\n";
                std::snprintf(line, sizeof line, "%10zu %9.0fx %12.4g %10.4g %12.4g %12.3g %8.2f\n", r.bytes,
                              static_cast<double>(input_bytes) / static_cast<double>(r.bytes),
                              r.metrics.cos_rmse_rel.mean, r.metrics.log_rmse.mean, d.cos_rmse_rel.mean, r.eval_rate,
                              r.build_seconds);
                std::cout << line;
            } catch (const Error& e) {
                csv << sweep_csv_row("coated-diffuse", "merl", spec, input_bytes, nullptr, e.what())
                    << sweep_csv_directions(nullptr) << "\n";
                std::cout << "failed: " << e.what() << "\n";
                ++failed;
            }
        }
        save_text(csv_path, csv.str());
        std::cout << "   wrote " << csv_path << "\n";
        if (failed)
            throw Error("demo: " + std::to_string(failed) + " of " + std::to_string(built.size()) +
                        " representations could not be built (their rows above say why)");
        std::cout << "\noutputs are in " << std::filesystem::absolute(*out_dir).string() << "\n";
    });
}

}  // namespace brdfz::cli
