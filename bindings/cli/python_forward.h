// Verbs whose work is done by the brdfz Python package (a dependency the C++ library does not have):
// the command runs the package's module with the user's arguments, and its messages are the user's.
#pragma once

#include <string>
#include <vector>

namespace brdfz::cli {

// Runs main(args) of the Python module `module` with the interpreter BRDFZ_PYTHON_EXECUTABLE names
// (default python3). A missing package is one line naming `verb` and what it `needs`. Returns when
// the module exits with 0; otherwise throws CLI::RuntimeError(1) (the module has reported why).
// SIGINT is left to the module (a server stops on Ctrl-C), not ending this process first.
void run_python(const std::string& verb, const std::string& module, const std::string& needs,
                const std::vector<std::string>& args);

}  // namespace brdfz::cli
