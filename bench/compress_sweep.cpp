// The compression benchmark: every representation setting over a set of materials, one CSV row each
// (columns below; the Python charts read this file). Numbers come from brdfz::trial(), the same
// measurement `brdfz compress` prints.
//
//   compress_sweep [--out sweep.csv] [--spec SPEC]... [FILE...]
// FILEs: any BRDF files (default: ../shared/data/rgl/*.bsdf and the MERL tables in $BRDFZ_MERL_DIR).
// --spec replaces the default list of settings (repeatable). A setting whose kind is not built into
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

const char* const kDefaultSpecs[] = {
    "tabular:res=90x90x180",        // the MERL grid in float32: the baseline
    "tabular:res=45x45x90",         "tabular:res=45x45x90,dtype=f16", "tabular:res=45x45x90,dtype=u8log",
    "tabular:res=32x32x64,dtype=f16", "tabular:res=32x32x64,dtype=u8log", "tabular:res=16x16x32,dtype=u8log",
    "bivariate:res=90x90",          "bivariate:res=90x90,dtype=u8log", "bivariate:res=32x32,dtype=f16",
    "svd:rank=1,space=log",         "svd:rank=2,space=log", "svd:rank=4,space=log", "svd:rank=8,space=log",
    "svd:rank=4,space=cos",         "nmf:rank=1", "nmf:rank=2", "nmf:rank=4",
    "analytic:lambert+ggx",         "analytic:lambert+ggx+ggx", "analytic:lambert+beckmann",
};

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

// CSV field: quoted when it holds a comma or a quote.
std::string field(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    bench::SweepArgs args = bench::parse_sweep_args(argc, argv, "compress_sweep.csv", kDefaultSpecs);
    const std::vector<std::string>& specs = args.specs;
    std::vector<fs::path>& files = args.files;
    const std::string& out_path = args.out;
    if (files.empty()) files = default_materials();
    if (files.empty()) {
        std::fprintf(stderr, "compress_sweep: no materials (no ../shared/data/rgl and no MERL tables); name files\n");
        return 2;
    }

    std::ofstream csv(out_path);
    csv << "material,format,repr,describe,bytes,input_bytes,ratio,cos_rmse,cos_rmse_rel,log_rmse,cbrt_rmse,"
           "eval_pairs_per_s,build_s,status\n";
    for (const fs::path& file : files) {
        const brdfz::Loaded in = brdfz::load(file.string());
        const auto input_bytes = fs::file_size(file);
        for (const std::string& spec : specs) {
            std::fprintf(stderr, "%s  %s ...", file.stem().c_str(), spec.c_str());
            csv << field(file.stem().string()) << "," << in.info.format << "," << field(spec) << ",";
            try {
                const brdfz::Trial t = brdfz::trial(*in.brdf, spec);
                std::string status = "ok";
                for (const std::string& n : t.notes) status += "; " + n;
                csv << field(t.describe) << "," << t.bytes << "," << input_bytes << ","
                    << num(static_cast<double>(input_bytes) / static_cast<double>(t.bytes)) << ","
                    << num(t.metrics.cos_rmse.mean) << "," << num(t.metrics.cos_rmse_rel.mean) << ","
                    << num(t.metrics.log_rmse.mean) << "," << num(t.metrics.cbrt_rmse.mean) << "," << num(t.eval_rate)
                    << "," << num(t.build_seconds) << "," << field(status) << "\n";
                std::fprintf(stderr, " %zu bytes, cos_rmse_rel %.4f, %.3g pairs/s, %.2f s\n", t.bytes,
                             t.metrics.cos_rmse_rel.mean, t.eval_rate, t.build_seconds);
            } catch (const std::exception& e) {
                csv << ",," << input_bytes << ",,,,,,,," << field(std::string("error: ") + e.what()) << "\n";
                std::fprintf(stderr, " error: %s\n", e.what());
            }
            csv.flush();
        }
    }
    std::fprintf(stderr, "wrote %s\n", out_path.c_str());
    return 0;
}
