// brdfz._core: the pybind11 module behind the brdfz package (bindings/python/brdfz/__init__.py).
// Library exceptions arrive in Python with their message:
//   brdfz::ValueError -> ValueError          brdfz::FormatError      -> brdfz.FormatError(ValueError)
//   brdfz::IoError    -> OSError             brdfz::UnsupportedError -> brdfz.UnsupportedError(ValueError)
// (FileNotFoundError, an OSError, when the file read does not exist: operations.cpp).
#include "brdfz/errors.h"
#include "module.h"

PYBIND11_MODULE(_core, m) {
    namespace py = pybind11;
    m.doc() = "brdfz: measured BRDFs, compactly stored (C++ core of the brdfz package)";
    m.attr("__version__") = BRDFZ_VERSION;
    // The bound on every `threads` argument (brdfz/control.h).
    m.attr("MAX_THREADS") = brdfz::kMaxThreads;

    py::register_exception<brdfz::FormatError>(m, "FormatError", PyExc_ValueError);
    py::register_exception<brdfz::UnsupportedError>(m, "UnsupportedError", PyExc_ValueError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const brdfz::ValueError& e) {
            py::set_error(PyExc_ValueError, e.what());
        } catch (const brdfz::IoError& e) {
            py::set_error(PyExc_OSError, e.what());
        }
    });

    brdfz::python::bind_brdf(m);
    brdfz::python::bind_operations(m);
    brdfz::python::bind_select(m);
}
