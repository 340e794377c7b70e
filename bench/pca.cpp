// PCA basis accuracy and cost: for each material, project it onto a basis (brdfz pca-train) at several
// k and compare the reconstruction with the material itself (brdfz/metrics.h, each bin of the
// reference's grid once, θ < 80°). Prints bytes per material (nbytes, and the size of its .brdfz file
// referencing the basis, written beside the basis and removed), cos_rmse_rel and log_rmse (channel
// means), and the time of projecting plus reconstructing, beside the time of reading the basis file.
//   pca BASIS.brdfz FILE... [--k 4,8,16,32]
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>

#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/pca.h"
#include "brdfz/tabulate.h"
#include "common.h"

int main(int argc, char** argv) {
    std::string basis_path;
    std::vector<std::string> files;
    std::vector<int> ks{4, 8, 16, 32};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--k" && i + 1 < argc) {
            ks.clear();
            std::stringstream s(argv[++i]);
            for (std::string part; std::getline(s, part, ',');) ks.push_back(std::atoi(part.c_str()));
        } else if (basis_path.empty()) {
            basis_path = a;
        } else {
            files.push_back(a);
        }
    }
    if (basis_path.empty() || files.empty()) {
        std::fprintf(stderr, "usage: %s BASIS.brdfz FILE... [--k 4,8,16,32]\n", argv[0]);
        return 2;
    }
    try {
        const auto t0 = bench::Clock::now();
        const std::shared_ptr<const brdfz::PcaBasis> basis = brdfz::container::read_pca_basis(basis_path);
        const double read_ms = bench::ms_between(t0, bench::Clock::now());
        std::printf("basis %s: %s, k_max %d, %zu kept bins, %zu bytes, read in %.0f ms (sha256 checked)\n",
                    basis_path.c_str(), basis->grid().str().c_str(), basis->k_max(), basis->kept_bins(), basis->nbytes(),
                    read_ms);
        const std::string scratch =
            (std::filesystem::path(basis_path).parent_path() / "pca-bench-material.brdfz").string();
        std::printf("%-34s %4s %7s %7s %12s %10s %10s %9s\n", "material", "k", "bytes", "file", "cos_rmse_rel",
                    "log_rmse", "clamped", "ms");
        for (const std::string& f : files) {
            const brdfz::Loaded in = brdfz::load(f);
            const auto* t = dynamic_cast<const brdfz::TabularBrdf*>(in.brdf.get());
            std::optional<brdfz::Table> tabulated;
            if (!t || !(t->table().grid() == basis->grid())) {
                brdfz::TabulateOptions o;
                o.grid = basis->grid();
                tabulated = brdfz::tabulate(*in.brdf, o).table;
            }
            const brdfz::Table& table = tabulated ? *tabulated : t->table();
            const std::string name = f.substr(f.find_last_of('/') + 1);
            for (int k : ks) {
                if (k > basis->k_max()) continue;
                const auto a = bench::Clock::now();
                const brdfz::PcaBrdf pca(basis, basis->project(table, k));
                const double ms = bench::ms_between(a, bench::Clock::now());
                const brdfz::Metrics m = brdfz::compare(*in.brdf, pca);
                brdfz::container::write(scratch, pca);
                const std::uintmax_t file_bytes = std::filesystem::file_size(scratch);
                std::filesystem::remove(scratch);
                std::printf("%-34s %4d %7zu %7ju %12.4f %10.5f %10zu %9.0f\n", name.c_str(), k, pca.nbytes(), file_bytes,
                            m.cos_rmse_rel.mean, m.log_rmse.mean, pca.counts().clamped, ms);
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "pca: %s\n", e.what());
        return 1;
    }
    return 0;
}
