// brdfz convert IN OUT: formats from the extensions; non-tabular sources are tabulated.
#include <iostream>

#include "commands.h"
#include "output.h"

namespace brdfz::cli {

void add_convert(CLI::App& app) {
    struct Args {
        std::string in, out, res;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("convert", "convert between formats (MERL -> MERL, RGL -> MERL)");
    cmd->add_option("IN", args->in, "input file")->required();
    cmd->add_option("OUT", args->out, "output file")->required();
    cmd->add_option("--res", args->res, "table resolution NHxNDxNP (default: the input's, or 90x90x180)");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        const Loaded in = load(args->in, args->load);
        SaveOptions save_options;
        if (!args->res.empty()) save_options.grid = parse_resolution(args->res);
        save_options.progress = progress_bar("tabulating");
        const ValidityCounts c = save(*in.brdf, args->out, save_options);
        std::cout << "wrote " << args->out << ": " << c.valid << " valid bins";
        if (c.below_horizon) std::cout << ", " << c.below_horizon << " below the horizon";
        if (c.clamped) std::cout << ", " << c.clamped << " negative clamped to 0";
        if (c.negative + c.nan + c.inf)
            std::cout << ", invalid: " << c.negative << " negative, " << c.nan << " NaN, " << c.inf << " Inf";
        std::cout << "\n";
    });
}

}  // namespace brdfz::cli
