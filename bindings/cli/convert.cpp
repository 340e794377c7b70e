// brdfz convert IN OUT: between every readable and writable format, from the extensions or --from /
// --to. A representation the output format cannot hold is tabulated (on --res, default 90x90x180).
//   read:  .binary (MERL), .bsdf (RGL), .brdfz, .exr, .json (analytic model)
//   write: .binary, .bsdf (RGB, for Mitsuba 3 and pbrt-v4; anisotropic with --phi-i), .brdfz, .exr, .json
//          (analytic only)
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
    CLI::App* cmd = app.add_subcommand("convert", "convert between formats (merl, rgl, brdfz, exr, json)");
    cmd->add_option("IN", args->in, "input file")->required();
    cmd->add_option("OUT", args->out, "output file")->required();
    cmd->add_option("--res", args->res, "table resolution NHxNDxNP (default: the input's, or 90x90x180)");
    cmd->add_option("--from", args->from, "input format (default: from the extension of IN)");
    cmd->add_option("--to", args->to, "output format (default: from the extension of OUT)");
    cmd->add_option("--phi-i", args->phi_i,
                    ".bsdf output: φi slices (1: isotropic, the default; 3..4096: an anisotropic file)");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        const Loaded in = load_as(args->from.empty() ? format_of(args->in) : args->from, args->in, args->load);
        SaveOptions save_options;
        save_options.format = args->to;
        save_options.rgl_phi_i = args->phi_i;
        save_options.source = args->in;
        save_options.source_format = in.info.format;
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
