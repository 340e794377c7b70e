// brdfz export IN -o OUT.brdfzrt [--repr SPEC]: the runtime layout (formats/SPEC.md §6) of any readable
// material, or of its SPEC representation (brdfz compress's specs; measurements need analytic:MODEL),
// what brdfz::runtime and a GPU read.
// brdfz export IN -o DIR --target T [--repr SPEC]: that layout with the shader module, descriptor and
// integration note for a GPU renderer. The shader code comes from the Slang compiler, which ships in a
// Python wheel, so this runs `python -m brdfz.gpu export` (bindings/python/brdfz/gpu/export.py).
#include <filesystem>
#include <iostream>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/runtime_layout.h"
#include "commands.h"
#include "output.h"
#include "python_forward.h"

namespace brdfz::cli {

namespace {

const std::vector<std::string> kGpuTargets = {"glsl", "essl", "hlsl", "wgsl", "cuda", "metal", "slang"};

}  // namespace

void add_export(CLI::App& app) {
    struct Args {
        std::string in, out, repr, target;
        LoadOptions load;
        int threads = 0;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("export", "write the runtime layout (.brdfzrt) brdfz::runtime and GPUs read");
    cmd->add_option("IN", args->in, "BRDF file, or measurements (.brdf, .dat: with --repr analytic:MODEL)")->required();
    cmd->add_option("-o,--output", args->out, "output file (.brdfzrt); with --target, the folder to write")->required();
    cmd->add_option("--repr", args->repr, "build this representation first (brdfz representations lists them)");
    cmd->add_option("--target", args->target,
                    "shading language of a GPU export: the buffers, the shader module, brdfz.json and INTEGRATION.md "
                    "(runs python -m brdfz.gpu export)")
        ->check(CLI::IsMember(kGpuTargets));
    cmd->add_option("--threads", args->threads, "worker threads for building (0: one per core)")->check(CLI::NonNegativeNumber);
    add_load_options(cmd, args->load);
    cmd->callback([args, cmd] {
        if (!args->repr.empty()) ReprSpec::parse(args->repr);  // a malformed spec before any work
        if (!args->target.empty()) {
            if (cmd->count("--lookup") + cmd->count("--bin-position") > 0)
                throw ValueError("export --target reads IN as brdfz.load does: --lookup and --bin-position apply only "
                                 "to a .brdfzrt export");
            std::vector<std::string> forward = {"export", args->in, "-o", args->out, "--target", args->target,
                                                "--threads", std::to_string(args->threads)};
            if (!args->repr.empty()) forward.insert(forward.end(), {"--repr", args->repr});
            run_python("export --target", "brdfz.gpu.__main__",
                       "the brdfz Python package and the Slang compiler (slangpy)", forward);
            return;
        }
        CompressOptions options = with_file_access({});
        options.threads = args->threads;
        options.progress = progress_bar("building");
        std::unique_ptr<Brdf> built;
        std::string describe;
        if (holds_measurements(args->in)) {
            if (args->repr.empty()) throw ValueError(args->in + ": measurements need a representation, e.g. --repr analytic:lambert+ggx");
            built = compress(load_measurements(args->in).set, args->repr, options).brdf;
        } else {
            Loaded in = load(args->in, args->load);
            built = args->repr.empty() ? std::move(in.brdf) : compress(*in.brdf, args->repr, options).brdf;
        }
        describe = built->describe() + (args->repr.empty() ? "" : " (" + args->repr + ")");
        runtime_layout::write(args->out, *built, describe);
        std::cout << "wrote " << args->out << ": " << std::filesystem::file_size(args->out) << " bytes, " << describe
                  << "\n";
    });
}

}  // namespace brdfz::cli
