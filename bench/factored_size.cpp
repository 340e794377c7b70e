// Size against accuracy of factored representations: for each material file and each spec, the
// stored bytes, cos_rmse_rel (metrics.h, mean and worst of the channels, θ < 80°) against the source and
// the build time. Any compress() spec works, not only factored ones. Target (#4): ≤ 16 KB per material within 2% cos_rmse_rel on every shared RGL material.
//
// Usage: factored_size FILE... [--spec SPEC]...   (default: the spec list below)
// Prints a Markdown table.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"

int main(int argc, char** argv) try {
    std::vector<std::string> files, specs;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--spec" && i + 1 < argc)
            specs.push_back(argv[++i]);
        else
            files.push_back(a);
    }
    if (files.empty()) {
        std::fprintf(stderr, "usage: %s FILE... [--spec SPEC]...\n", argv[0]);
        return 2;
    }
    if (specs.empty())
        specs = {
            "svd:rank=8,space=cos,colour=shared,res=32x16x32",
            "svd:rank=7,space=log,colour=shared,res=32x16x32",
            "svd:rank=3,space=cos,layout=hd_p,colour=shared,res=32x32x16",
            "svd:rank=4,space=cos,res=32x16x16",
            "nmf:rank=8,space=cos,colour=shared,res=32x16x32",
        };
    std::printf("| material | spec | bytes | cos_rmse_rel | worst channel | build s | notes |\n"
                "|---|---|---|---|---|---|---|\n");
    for (const std::string& file : files) {
        const brdfz::Loaded source = brdfz::load(file);
        const std::string name = file.substr(file.find_last_of('/') + 1);
        for (const std::string& spec : specs) {
            const brdfz::Compressed c = brdfz::compress(*source.brdf, spec);
            const brdfz::Metrics m = brdfz::compare(*source.brdf, *c.brdf);
            std::string notes;
            for (const std::string& n : c.notes) notes += (notes.empty() ? "" : "; ") + n;
            const brdfz::PerChannel& rel = m.cos_rmse_rel;
            std::printf("| %s | `%s` | %zu | %.4f | %.4f | %.2f | %s |\n", name.c_str(), spec.c_str(), c.brdf->nbytes(),
                        rel.mean, std::max({rel.r, rel.g, rel.b}), c.build_seconds, notes.c_str());
            std::fflush(stdout);
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "factored_size: %s\n", e.what());
    return 1;
}
