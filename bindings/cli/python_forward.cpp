#include "python_forward.h"

#include <spawn.h>
#include <sys/wait.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "brdfz/errors.h"

extern char** environ;

namespace brdfz::cli {

namespace {

// Imports the module's main, reporting a missing package in one line rather than as a traceback.
std::string bootstrap(const std::string& verb, const std::string& module, const std::string& needs) {
    return "import sys\n"
           "try:\n"
           "    from " + module + " import main\n"
           "except ImportError as e:\n"
           "    print(f'brdfz " + verb + " needs " + needs + ": {e}; "
           "PYTHONPATH says where brdfz is, BRDFZ_PYTHON_EXECUTABLE which interpreter', file=sys.stderr)\n"
           "    sys.exit(1)\n"
           "sys.exit(main(sys.argv[1:]))\n";
}

// Restores a signal's disposition when it goes out of scope.
class IgnoreSignal {
public:
    explicit IgnoreSignal(int signal) : signal_(signal) { old_ = std::signal(signal, SIG_IGN); }
    ~IgnoreSignal() { std::signal(signal_, old_); }
    IgnoreSignal(const IgnoreSignal&) = delete;
    IgnoreSignal& operator=(const IgnoreSignal&) = delete;

private:
    int signal_;
    void (*old_)(int);
};

}  // namespace

void run_python(const std::string& verb, const std::string& module, const std::string& needs,
                const std::vector<std::string>& args) {
    const char* env = std::getenv("BRDFZ_PYTHON_EXECUTABLE");
    const std::string python = env && *env ? env : "python3";
    std::vector<std::string> all = {python, "-c", bootstrap(verb, module, needs)};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::cout.flush();

    // The child gets SIGINT's default (an ignored signal would be inherited), this process ignores
    // it while the child runs, so that Ctrl-C reaches Python alone.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
    IgnoreSignal ignore(SIGINT);
    pid_t pid = 0;
    const int spawned = posix_spawnp(&pid, python.c_str(), nullptr, &attr, argv.data(), environ);
    posix_spawnattr_destroy(&attr);
    if (spawned != 0)
        throw ValueError(verb + " runs " + module + " with " + python + ": " + std::strerror(spawned) +
                         " (BRDFZ_PYTHON_EXECUTABLE names the interpreter)");
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) throw ValueError(verb + ": waiting for Python: " + std::strerror(errno));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw CLI::RuntimeError(1);
}

}  // namespace brdfz::cli
