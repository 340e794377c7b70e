// brdfz view FILE... [--compare SPEC...] [--port N] [--html OUT]: a local web page of materials and
// their representations (plots, and a lit sphere the browser renders with the exported shaders). The
// page is built by the brdfz Python package (bindings/python/brdfz/view), which this runs.
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "commands.h"
#include "python_forward.h"

namespace brdfz::cli {

void add_view(CLI::App& app) {
    struct Args {
        std::vector<std::string> files, compare;
        std::string html;
        int port = 0, size = 256, env_samples = 64, passes = 16;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "view", "a local web page of materials and representations, served on 127.0.0.1 or written to --html "
                "(runs python -m brdfz.view)");
    cmd->add_option("FILE", args->files, "materials to show (any file brdfz reads)")->required();
    cmd->add_option("--compare", args->compare, "representations of the first FILE to show beside it (compress specs)");
    cmd->add_option("--port", args->port, "port on 127.0.0.1 (default: a free one; the URL is printed)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--html", args->html, "write one self-contained page that opens from disk, and exit");
    cmd->add_option("--size", args->size, "the sphere's side in pixels")->check(CLI::Range(1, 2048));
    cmd->add_option("--env-samples", args->env_samples, "sky draws per pixel of the sphere and pass")->check(CLI::Range(0, 4096));
    cmd->add_option("--passes", args->passes, "passes of sky draws the spheres and their error average, shown as they come")
        ->check(CLI::Range(1, 1024));
    cmd->callback([args] {
        for (const std::string& spec : args->compare) ReprSpec::parse(spec);  // a malformed spec before any work
        std::vector<std::string> forward = args->files;
        if (!args->compare.empty()) {
            forward.push_back("--compare");
            forward.insert(forward.end(), args->compare.begin(), args->compare.end());
        }
        forward.insert(forward.end(), {"--port", std::to_string(args->port), "--size", std::to_string(args->size),
                                       "--env-samples", std::to_string(args->env_samples), "--passes",
                                       std::to_string(args->passes)});
        if (!args->html.empty()) forward.insert(forward.end(), {"--html", args->html});
        run_python("view", "brdfz.view", "the brdfz Python package", forward);
    });
}

}  // namespace brdfz::cli
