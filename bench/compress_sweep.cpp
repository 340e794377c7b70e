// The compression benchmark: every representation setting over a set of materials, one CSV row each
// (brdfz::kSweepCsvHeader, select.h; python -m brdfz.bench --from-csv charts it). Numbers come from brdfz::trial(), the same
// measurement `brdfz compress` prints.
//
//   compress_sweep [--out sweep.csv] [--spec SPEC]... [FILE...]
// FILEs: any BRDF files (default: ../shared/data/rgl/*.bsdf and the MERL tables in $BRDFZ_MERL_DIR).
// --spec replaces the default list of settings, brdfz::benchmark_specs() (repeatable). A setting whose kind is not built into
// this library, or that fails on a material, gets a row with status "error: ..." and empty numbers.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "brdfz/formats/io.h"
#include "brdfz/select.h"
#include "common.h"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> default_materials() {
    std::vector<fs::path> out;
    const auto add_dir = [&](const fs::path& dir, const std::string& ext) {
        if (!fs::is_directory(dir)) return;
        std::vector<fs::path> found;
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ext) found.push_back(e.path());
        std::sort(found.begin(), found.end());
        out.insert(out.end(), found.begin(), found.end());
    };
    add_dir(fs::path(BRDFZ_SOURCE_DIR) / ".." / "shared" / "data" / "rgl", ".bsdf");
    const char* merl = std::getenv("BRDFZ_MERL_DIR");
    add_dir(merl ? fs::path(merl) : fs::path(BRDFZ_BINARY_DIR) / "merl-tables", ".binary");
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    bench::SweepArgs args = bench::parse_sweep_args(argc, argv, "compress_sweep.csv", brdfz::benchmark_specs());
    const std::vector<std::string>& specs = args.specs;
    std::vector<fs::path>& files = args.files;
    const std::string& out_path = args.out;
    if (files.empty()) files = default_materials();
    if (files.empty()) {
        std::fprintf(stderr, "compress_sweep: no materials (no ../shared/data/rgl and no MERL tables); name files\n");
        return 2;
    }

    std::ofstream csv(out_path);
    csv << brdfz::kSweepCsvHeader << "\n";
    for (const fs::path& file : files) {
        const brdfz::Loaded in = brdfz::load(file.string());
        const auto input_bytes = fs::file_size(file);
        for (const std::string& spec : specs) {
            std::fprintf(stderr, "%s  %s ...", file.stem().c_str(), spec.c_str());
            try {
                const brdfz::Trial t = brdfz::trial(*in.brdf, spec);
                csv << brdfz::sweep_csv_row(file.stem().string(), in.info.format, spec, input_bytes, &t) << "\n";
                std::fprintf(stderr, " %zu bytes, cos_rmse_rel %.4f, %.3g pairs/s, %.2f s\n", t.bytes,
                             t.metrics.cos_rmse_rel.mean, t.eval_rate, t.build_seconds);
            } catch (const std::exception& e) {
                csv << brdfz::sweep_csv_row(file.stem().string(), in.info.format, spec, input_bytes, nullptr, e.what())
                    << "\n";
                std::fprintf(stderr, " error: %s\n", e.what());
            }
            csv.flush();
        }
    }
    std::fprintf(stderr, "wrote %s\n", out_path.c_str());
    return 0;
}
