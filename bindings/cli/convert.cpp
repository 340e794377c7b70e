// brdfz convert IN OUT: between every readable and writable format (`brdfz formats`), from the
// extensions or --from / --to. A representation the output format cannot hold is tabulated (on --res,
// default 90x90x180).
#include <iostream>

#include "commands.h"
#include "output.h"

namespace brdfz::cli {

void add_convert(CLI::App& app) {
    struct Args {
        std::string in, out, res, from, to;
        LoadOptions load;
        int phi_i = 1;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("convert", "convert between formats (brdfz formats lists them)");
    cmd->add_option("IN", args->in, "input file")->required();
    cmd->add_option("OUT", args->out, "output file")->required();
    cmd->add_option("--res", args->res, "table resolution NHxNDxNP (default: the input's, or 90x90x180)");
    cmd->add_option("--from", args->from, "input format (default: from the extension of IN)");
    cmd->add_option("--to", args->to, "output format (default: from the extension of OUT)");
    cmd->add_option("--phi-i", args->phi_i,
                    ".bsdf output: φi slices (1: isotropic, the default; 3..4096: an anisotropic file)");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        ConvertOptions options;
        options.from = args->from;
        options.load = args->load;
        options.save.format = args->to;
        options.save.rgl_phi_i = args->phi_i;
        if (!args->res.empty()) options.save.grid = parse_resolution(args->res);
        options.save.progress = progress_bar("tabulating");
        const ValidityCounts c = convert(args->in, args->out, options);
        std::cout << "wrote " << args->out << ": " << c.valid << " valid entries";
        if (c.below_horizon) std::cout << ", " << c.below_horizon << " below the horizon";
        if (c.clamped) std::cout << ", " << c.clamped << " negative clamped to 0";
        if (c.negative + c.nan + c.inf)
            std::cout << ", invalid: " << c.negative << " negative, " << c.nan << " NaN, " << c.inf << " Inf";
        std::cout << "\n";
    });
}

}  // namespace brdfz::cli
