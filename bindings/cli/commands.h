// Each subcommand registers itself on the app; its callback does the work and throws on failure.
#pragma once

#include <CLI/CLI.hpp>

namespace brdfz::cli {

void add_info(CLI::App& app);
void add_convert(CLI::App& app);
void add_eval(CLI::App& app);
void add_diff(CLI::App& app);
void add_demo(CLI::App& app);
void add_validate(CLI::App& app);
void add_sample(CLI::App& app);
void add_fit(CLI::App& app);
void add_compress(CLI::App& app);
void add_pca_train(CLI::App& app);
void add_formats(CLI::App& app);
void add_representations(CLI::App& app);
void add_export(CLI::App& app);
void add_view(CLI::App& app);

}  // namespace brdfz::cli
