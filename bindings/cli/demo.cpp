// brdfz demo: the main job on the embedded default material, with no data files.
// A built-in coated-diffuse BRDF is measured by the virtual gonioreflectometer at MERL resolution,
// written as a MERL table, read back (checked bit-identical), reported, and compared with the
// analytic original.
#include <chrono>
#include <filesystem>
#include <iostream>

#include "brdfz/errors.h"
#include "brdfz/formats/merl.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/tabulate.h"
#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {

void add_demo(CLI::App& app) {
    auto out_dir = std::make_shared<std::string>("brdfz-demo");
    CLI::App* cmd = app.add_subcommand("demo", "run the pipeline on a built-in material (no data files needed)");
    cmd->add_option("--out", *out_dir, "output folder")->capture_default_str();
    cmd->callback([out_dir] {
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
        std::cout << "\noutputs are in " << std::filesystem::absolute(*out_dir).string() << "\n";
    });
}

}  // namespace brdfz::cli
