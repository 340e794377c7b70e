// brdfz info FILE [--json]
#include <iostream>

#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {

void add_info(CLI::App& app) {
    struct Args {
        std::string file;
        bool json = false;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("info", "format, dimensions, validity counts, value range, albedo, size");
    cmd->add_option("FILE", args->file, "input file")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args] { print_info(args->file, load(args->file, args->load), args->json, std::cout); });
}

}  // namespace brdfz::cli
