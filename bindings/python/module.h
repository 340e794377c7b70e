// Declarations shared by the translation units of brdfz._core.
#pragma once

#include <pybind11/pybind11.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "brdfz/brdf.h"
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

// Bridges a Python progress callable (fraction done, 0..1] into the library's progress hook, which
// runs on worker threads while the GIL is released. A Python exception raised by the callable is
// kept and re-raised by rethrow() once the operation is over (the library has no cancellation).
class Progress {
public:
    explicit Progress(py::object callable);
    // The hook to pass in the library's options; empty when there is no callable.
    std::function<void(double)> hook();
    // Re-raises the callable's first exception, if any.
    void rethrow();

private:
    struct State;
    std::shared_ptr<State> state_;
};

}  // namespace brdfz::python
