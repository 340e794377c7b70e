// brdfz export IN -o OUT.brdfzrt [--repr SPEC]: the runtime layout (formats/SPEC.md §6) of any readable
// material, or of its SPEC representation (brdfz compress's specs; measurements need analytic:MODEL),
// what brdfz::runtime and a GPU read.
// brdfz export IN -o DIR --target T [--repr SPEC]: that layout with the shader module, descriptor and
// integration note for a GPU renderer. The shader code comes from the Slang compiler, which ships in a
// Python wheel, so this runs `python -m brdfz.gpu export` (bindings/python/brdfz/gpu/export.py).
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/runtime_layout.h"
#include "commands.h"
#include "output.h"

extern char** environ;

namespace brdfz::cli {

namespace {

const std::vector<std::string> kGpuTargets = {"glsl", "essl", "hlsl", "wgsl", "cuda", "metal", "slang"};

// A missing package is reported in one line rather than as Python's traceback.
constexpr const char* kBootstrap =
    "import sys\n"
    "try:\n"
    "    from brdfz.gpu.__main__ import main\n"
    "except ImportError as e:\n"
    "    print(f'brdfz export --target needs the brdfz Python package and the Slang compiler (slangpy): {e}; "
    "PYTHONPATH says where brdfz is, BRDFZ_PYTHON_EXECUTABLE which interpreter', file=sys.stderr)\n"
    "    sys.exit(1)\n"
    "sys.exit(main(sys.argv[1:]))\n";

// Runs the Python exporter with these arguments; its messages are the user's. Non-zero exit: a failure
// it has already reported.
void run_python_export(const std::vector<std::string>& args) {
    const char* env = std::getenv("BRDFZ_PYTHON_EXECUTABLE");
    const std::string python = env && *env ? env : "python3";
    std::vector<std::string> all = {python, "-c", kBootstrap, "export"};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::cout.flush();
    pid_t pid = 0;
    const int spawned = posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ);
    if (spawned != 0)
        throw ValueError("export --target runs " + python + " -m brdfz.gpu export: " + std::strerror(spawned) +
                         " (BRDFZ_PYTHON_EXECUTABLE names the interpreter)");
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) throw ValueError(std::string("export --target: waiting for Python: ") + std::strerror(errno));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw CLI::RuntimeError(1);
}

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
            std::vector<std::string> forward = {args->in, "-o", args->out, "--target", args->target,
                                                "--threads", std::to_string(args->threads)};
            if (!args->repr.empty()) forward.insert(forward.end(), {"--repr", args->repr});
            run_python_export(forward);
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
