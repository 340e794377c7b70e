// brdfz pca-train DIR... -o BASIS [--k-max 32] [--res 90x90x180] [--symmetry reciprocal|none]
// Learns a PCA basis (brdfz/repr/pca.h) from every BRDF file in the given directories (or the files
// given) and writes it as a basis file (formats/SPEC.md, "pca") for `compress --repr pca:basis=BASIS`.
// Tables on the basis's grid are used as they are; anything else is tabulated onto it.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "brdfz/errors.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/tabulate.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

// The BRDF files among `inputs`: directories are listed (files whose extension a reader knows, by
// name), files are taken as given.
std::vector<std::string> training_files(const std::vector<std::string>& inputs) {
    std::vector<std::string> files;
    for (const std::string& in : inputs) {
        if (!std::filesystem::is_directory(in)) {
            files.push_back(in);
            continue;
        }
        std::vector<std::string> found;
        for (const auto& e : std::filesystem::directory_iterator(in)) {
            if (!e.is_regular_file()) continue;
            try {
                if (!holds_measurements(e.path().string())) found.push_back(e.path().string());
            } catch (const FormatError&) {
                // not a BRDF file (unknown extension): skipped
            }
        }
        std::sort(found.begin(), found.end());
        if (found.empty()) throw ValueError(in + ": no BRDF files in this directory");
        files.insert(files.end(), found.begin(), found.end());
    }
    return files;
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

}  // namespace

void add_pca_train(CLI::App& app) {
    struct Args {
        std::vector<std::string> in;
        std::string out, res, symmetry;
        bool json = false;
        LoadOptions load;
        PcaTrainOptions train;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("pca-train", "learn a PCA basis from a set of materials (for --repr pca:basis=FILE)");
    cmd->add_option("DIR", args->in, "directories of BRDF files (or the files themselves)")->required();
    cmd->add_option("-o,--out", args->out, "basis file to write (.brdfz)")->required();
    cmd->add_option("--k-max", args->train.k_max, "components kept (at most one fewer than the materials)")
        ->capture_default_str();
    cmd->add_option("--res", args->res, "grid of the basis, e.g. 45x45x90 (default: the first table's, else 90x90x180)");
    cmd->add_option("--symmetry", args->symmetry,
                    "the basis's phi_d axis: reciprocal ([0, pi)) or none ([0, 2pi)); default: the grid's")
        ->check(CLI::IsMember({"reciprocal", "none"}));
    cmd->add_option("--epsilon", args->train.epsilon, "offset of the log mapping, in 1/sr")->capture_default_str();
    cmd->add_option("--max-invalid", args->train.max_invalid_fraction,
                    "drop a bin invalid in more than this fraction of the materials")
        ->capture_default_str();
    add_threads_option(cmd, args->train.threads);
    cmd->add_flag("--json", args->json, "print the report as JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        if (format_of(args->out, Access::Write) != "brdfz") throw ValueError(args->out + ": a basis is written as a .brdfz file");
        check_output(args->out);
        const std::vector<std::string> files = training_files(args->in);
        if (files.size() < 2) throw ValueError("pca-train needs at least 2 materials, got " + std::to_string(files.size()));
        const auto start = std::chrono::steady_clock::now();

        std::optional<GridSpec> grid;
        if (!args->res.empty()) grid = parse_resolution(args->res);
        std::vector<Table> tables;
        tables.reserve(files.size());
        const auto loading = progress_bar("loading");
        for (std::size_t i = 0; i < files.size(); ++i) {
            Loaded l = load(files[i], args->load);
            const Table* t = l.brdf->stored_table();
            if (!grid) grid = t ? t->grid() : GridSpec{};
            if (!args->symmetry.empty()) grid->symmetry = parse_symmetry(args->symmetry);
            if (t && t->grid() == *grid) {
                tables.push_back(*t);
            } else {
                TabulateOptions tab;
                tab.grid = *grid;
                tab.threads = args->train.threads;
                tables.push_back(tabulate(*l.brdf, tab).table);
            }
            if (loading) loading(static_cast<double>(i + 1) / files.size());
        }
        const double load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        std::vector<const Table*> ptrs;
        for (const Table& t : tables) ptrs.push_back(&t);
        PcaTrainOptions o = args->train;
        o.progress = progress_bar("training");
        PcaTrainReport report;
        PcaBasis trained = train_pca_basis(ptrs, o, &report);
        tables.clear();
        const double train_seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - load_seconds;
        const std::shared_ptr<const PcaBasis> basis = container::write_pca_basis(args->out, std::move(trained));
        const std::string& hash = basis->origin().sha256;
        const std::uintmax_t file_bytes = std::filesystem::file_size(args->out);

        // Cumulative share of the training set's variance the first k components explain.
        std::vector<double> explained;
        double sum = 0;
        for (double v : report.variances) explained.push_back((sum += v) / report.total_variance);
        if (args->json) {
            JsonWriter j(std::cout);
            j.begin_object();
            j.key("output").value(args->out);
            j.key("sha256").value(hash);
            j.key("materials").begin_array();
            for (const std::string& f : files) j.value(f);
            j.end_array();
            j.key("grid").value(basis->grid().str());
            j.key("k_max").value(static_cast<std::size_t>(basis->k_max()));
            j.key("kept_bins").value(report.kept_bins);
            j.key("dropped_bins").value(report.dropped_bins);
            j.key("imputed_values").value(report.imputed_values);
            j.key("explained_variance").begin_array();
            for (double e : explained) j.value(e);
            j.end_array();
            j.key("basis_nbytes").value(basis->nbytes());
            j.key("file_bytes").value(static_cast<std::size_t>(file_bytes));
            j.key("load_seconds").value(load_seconds);
            j.key("train_seconds").value(train_seconds);
            j.end_object();
            std::cout << "\n";
            return;
        }
        std::cout << "pca-train: " << files.size() << " materials on " << basis->grid().str() << "\n"
                  << "  bins        " << report.kept_bins << " kept, " << report.dropped_bins << " dropped, "
                  << report.imputed_values << " missing values set to the median\n"
                  << "  components  " << basis->k_max() << "; variance explained";
        for (std::size_t k = 1; k <= explained.size(); k *= 2)
            std::cout << "  k=" << k << " " << fmt("%.1f%%", 100.0 * explained[k - 1]);
        std::cout << "\n  basis       " << basis->nbytes() << " bytes (" << file_bytes << " in the file), sha256 " << hash
                  << "\n  time        " << fmt("%.1f", load_seconds) << " s loading, " << fmt("%.1f", train_seconds)
                  << " s training\n  wrote " << args->out << "\n";
    });
}

}  // namespace brdfz::cli
