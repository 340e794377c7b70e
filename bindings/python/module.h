// Declarations shared by the translation units of brdfz._core.
#pragma once

#include <pybind11/pybind11.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "brdfz/brdf.h"
#include "brdfz/control.h"
#include "brdfz/errors.h"
#include "brdfz/metrics.h"

namespace brdfz::python {

namespace py = pybind11;

// Python owns every Brdf through a shared_ptr, so results (fit, compress, tabulate) can outlive
// the objects they were built from and numpy views of a table can keep their Brdf alive.
using BrdfPtr = std::shared_ptr<Brdf>;

void bind_brdf(py::module_& m);
void bind_operations(py::module_& m);
void bind_select(py::module_& m);

// Brdf.parts() and Brdf.sampler_parts() (parts.cpp): a dict, or None for kinds without parts.
std::optional<py::dict> brdf_parts(const BrdfPtr& brdf);
std::optional<py::dict> sampler_parts(const BrdfPtr& brdf);

// The metric options every measuring function takes (metrics.h): max_theta in degrees, over "grid" or
// "directions", the number of direction pairs and their seed.
MetricOptions metric_options(double max_theta, int threads, const std::string& over, std::size_t directions,
                             std::uint64_t seed);

// A library IoError about a file that does not exist becomes FileNotFoundError (an OSError), with
// the library's message; every other error goes to the module's translator (_core.cpp).
template <typename Fn>
auto reading(const std::filesystem::path& path, Fn&& fn) {
    try {
        return fn();
    } catch (const IoError& e) {
        std::error_code ec;
        if (!std::filesystem::exists(path, ec)) {
            PyErr_SetString(PyExc_FileNotFoundError, e.what());
            throw py::error_already_set();
        }
        throw;
    }
}

// Library work that Python can stop. run(fn) calls fn with the GIL released under a stop check
// (brdfz/control.h, which the library polls between items of work): a signal whose handler raises
// (Ctrl-C's KeyboardInterrupt) stops the work at the library's next poll on the calling thread (where
// the handlers are run, at most every kSignalPoll), a progress callable (progress()) or another
// callback (call()) that raises stops it at that call. The exception is raised
// once the library has unwound; an operation stopped so writes no file (writers commit an output only
// when it is complete). Python runs signal handlers on its main thread only: work called from another
// thread stops for its callables' exceptions, not for signals.
class Interruptible {
public:
    static constexpr std::chrono::milliseconds kSignalPoll{20};

    explicit Interruptible(py::object progress = py::none());
    // The library's progress hook (fraction done, 0..1], called from worker threads): calls the
    // callable holding the GIL, one call at a time. Empty without a callable.
    std::function<void(double)> progress();
    // fn() holding the GIL, for a callback the library calls while run() works; a Python exception
    // from it stops the work.
    void call(const std::function<void()>& fn);

    template <typename Fn>
    auto run(Fn&& fn) -> decltype(fn()) {
        const StopScope scope(stop_check());
        try {
            py::gil_scoped_release release;
            return fn();
        } catch (const Stopped&) {
            raise();
        }
    }

private:
    // Thrown through the library to stop it; not a brdfz::Error (or std::exception), so that nothing
    // on the way takes it for a failure of its own.
    struct Stopped {};
    struct State;

    StopCheck stop_check();
    [[noreturn]] void raise();

    std::shared_ptr<State> state_;
};

}  // namespace brdfz::python
