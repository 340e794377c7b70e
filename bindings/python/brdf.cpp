// brdfz.Brdf: batched eval / eval_cos / pdf / sample on numpy arrays. Shapes and dtypes are checked
// with the GIL held; then, with the GIL released, rows are normalised in blocks and handed to the
// library's batch kernels.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/simd.h"
#include "module.h"
#include "rows.h"

namespace brdfz::python {

// Any Python object taken as an array argument: checked by as_rows (ValueError, not pybind11's
// TypeError, for anything but a float32/float64 (N, k) array); typed as an array in the stubs.
struct ArrayArg {
    py::object obj;
};

}  // namespace brdfz::python

namespace pybind11::detail {
template <>
struct type_caster<brdfz::python::ArrayArg> {
    PYBIND11_TYPE_CASTER(brdfz::python::ArrayArg, const_name("numpy.typing.NDArray[numpy.floating]"));
    bool load(handle src, bool) {
        value.obj = reinterpret_borrow<object>(src);
        return true;
    }
};
}  // namespace pybind11::detail

namespace brdfz::python {
namespace {

using Array = py::array_t<double>;

// Pairs are normalised and evaluated in blocks: bounded scratch memory, and the normalised rows are
// still in cache when the kernel reads them.
constexpr std::size_t kBlock = 2048;

// Rows of an (N, cols) float32 or float64 array, C-contiguous in native byte order (copied only when
// the input is not).
struct Rows {
    py::array array;
    bool f32 = false;

    std::size_t size() const { return static_cast<std::size_t>(array.shape(0)); }
    template <typename T>
    const T* data() const {
        return static_cast<const T*>(array.data());
    }
};

// ValueError naming the argument for anything but a float32 / float64 array of shape (N, cols).
Rows as_rows(const ArrayArg& arg, const char* name, py::ssize_t cols) {
    const py::handle obj = arg.obj;
    const std::string expected = "shape (N, " + std::to_string(cols) + ")";
    if (!py::isinstance<py::array>(obj)) throw ValueError(std::string(name) + ": expected a numpy array of " + expected);
    const auto array = py::reinterpret_borrow<py::array>(obj);
    const py::dtype dtype = array.dtype();
    if (dtype.kind() != 'f' || (dtype.itemsize() != 4 && dtype.itemsize() != 8))
        throw ValueError(std::string(name) + ": expected float32 or float64, got " + py::str(dtype).cast<std::string>());
    if (array.ndim() != 2 || array.shape(1) != cols) {
        std::string shape;
        for (py::ssize_t k = 0; k < array.ndim(); ++k) shape += (k ? ", " : "") + std::to_string(array.shape(k));
        if (array.ndim() == 1) shape += ",";
        throw ValueError(std::string(name) + ": expected " + expected + ", got (" + shape + ")");
    }
    if (dtype.itemsize() == 4) return {py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array), true};
    return {py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array), false};
}

void check_lengths(const Rows& a, const char* a_name, const Rows& b, const char* b_name) {
    if (a.size() != b.size())
        throw ValueError(std::string(a_name) + " and " + b_name + " have different lengths (" + std::to_string(a.size()) +
                         " and " + std::to_string(b.size()) + ")");
}

// Rows [begin, begin + out.size()) as unit directions (rows.h); ValueError naming the first bad row.
void directions(const Rows& rows, std::size_t begin, std::span<Vec3> out, const char* name) {
    const std::size_t bad = rows.f32 ? normalise_rows(rows.data<float>(), begin, out)
                                     : normalise_rows(rows.data<double>(), begin, out);
    if (bad < out.size())
        throw ValueError(std::string(name) + "[" + std::to_string(begin + bad) + "]: direction must be a finite non-zero vector");
}

// Rows [begin, begin + out.size()) of an (N, 2) array of random numbers; ValueError naming the row
// for one outside [0, 1) or NaN (the samplers would return a null sample for it, silently).
void pairs(const Rows& rows, std::size_t begin, std::span<std::array<double, 2>> out, const char* name) {
    if (rows.f32)
        copy_rows(rows.data<float>(), begin, out);
    else
        copy_rows(rows.data<double>(), begin, out);
    for (std::size_t k = 0; k < out.size(); ++k)
        for (double u : out[k])
            if (!(u >= 0.0 && u < 1.0)) {
                // The shortest text that reads back as u (to_string's six decimals print -1e-300 as -0.000000).
                char text[32];
                const auto end = std::to_chars(text, text + sizeof text, u).ptr;
                throw ValueError(std::string(name) + "[" + std::to_string(begin + k) + "]: " + std::string(text, end) +
                                 " is outside [0, 1)");
            }
}

Array new_rows(std::size_t n, py::ssize_t cols) {
    const auto rows = static_cast<py::ssize_t>(n);
    return cols == 1 ? Array(rows) : Array({rows, cols});
}

// fn(begin, a, b) for blocks of normalised directions from two row arrays, without the GIL.
template <typename Fn>
void for_blocks(const Rows& a, const char* a_name, const Rows& b, const char* b_name, Fn&& fn) {
    py::gil_scoped_release release;
    std::vector<Vec3> a_dirs(kBlock), b_dirs(kBlock);
    for (std::size_t begin = 0; begin < a.size(); begin += kBlock) {
        const std::size_t m = std::min(kBlock, a.size() - begin);
        const std::span<Vec3> a_block(a_dirs.data(), m), b_block(b_dirs.data(), m);
        directions(a, begin, a_block, a_name);
        directions(b, begin, b_block, b_name);
        fn(begin, a_block, b_block);
    }
}

template <bool Cosine>
Array eval(const Brdf& brdf, const ArrayArg& wi_obj, const ArrayArg& wo_obj) {
    const Rows wi = as_rows(wi_obj, "wi", 3), wo = as_rows(wo_obj, "wo", 3);
    check_lengths(wi, "wi", wo, "wo");
    Array out = new_rows(wi.size(), 3);
    auto* f = reinterpret_cast<Rgb*>(out.mutable_data());
    for_blocks(wi, "wi", wo, "wo", [&](std::size_t begin, std::span<const Vec3> wi_k, std::span<const Vec3> wo_k) {
        const std::span<Rgb> f_k(f + begin, wi_k.size());
        if constexpr (Cosine)
            brdf.eval_cos(wi_k, wo_k, f_k);
        else
            brdf.eval(wi_k, wo_k, f_k);
    });
    return out;
}

Array pdf(const Brdf& brdf, const ArrayArg& wo_obj, const ArrayArg& wi_obj) {
    const Rows wo = as_rows(wo_obj, "wo", 3), wi = as_rows(wi_obj, "wi", 3);
    check_lengths(wo, "wo", wi, "wi");
    Array out = new_rows(wo.size(), 1);
    double* p = out.mutable_data();
    for_blocks(wo, "wo", wi, "wi", [&](std::size_t begin, std::span<const Vec3> wo_k, std::span<const Vec3> wi_k) {
        brdf.pdf(wo_k, wi_k, std::span<double>(p + begin, wo_k.size()));
    });
    return out;
}

std::tuple<Array, Array, Array> sample(const Brdf& brdf, const ArrayArg& wo_obj, const ArrayArg& u_obj) {
    const Rows wo_rows = as_rows(wo_obj, "wo", 3), u_rows = as_rows(u_obj, "u", 2);
    check_lengths(wo_rows, "wo", u_rows, "u");
    const std::size_t n = wo_rows.size();
    Array wi_out = new_rows(n, 3), pdf_out = new_rows(n, 1), weight_out = new_rows(n, 3);
    double *wi = wi_out.mutable_data(), *p = pdf_out.mutable_data(), *weight = weight_out.mutable_data();
    {
        py::gil_scoped_release release;
        std::vector<Vec3> wo(kBlock);
        std::vector<std::array<double, 2>> u(kBlock);
        std::vector<BrdfSample> samples(kBlock);
        for (std::size_t begin = 0; begin < n; begin += kBlock) {
            const std::size_t m = std::min(kBlock, n - begin);
            directions(wo_rows, begin, std::span(wo.data(), m), "wo");
            pairs(u_rows, begin, std::span(u.data(), m), "u");
            brdf.sample(std::span(wo.data(), m), std::span(u.data(), m), std::span(samples.data(), m));
            split_samples(std::span(samples.data(), m), begin, wi, p, weight);
        }
    }
    return {wi_out, pdf_out, weight_out};
}

// A table's values as a read-only float32 view of shape (θh, θd, φd, 3) that keeps the Brdf alive;
// invalid entries are NaN (the table's validity mask).
std::optional<py::array_t<float>> table_view(const BrdfPtr& brdf) {
    const Table* stored = brdf->stored_table();
    if (!stored) return std::nullopt;
    const Table& t = *stored;
    const GridSpec& g = t.grid();
    const py::ssize_t f = sizeof(float);
    py::array_t<float> view({g.n_theta_h, g.n_theta_d, g.n_phi_d, 3},
                            {3 * f * g.n_phi_d * g.n_theta_d, 3 * f * g.n_phi_d, 3 * f, f}, t.data(), py::cast(brdf));
    view.attr("setflags")(py::arg("write") = false);
    return view;
}

std::optional<std::map<std::string, double>> parameters(const Brdf& brdf) {
    const auto* analytic = dynamic_cast<const AnalyticBrdf*>(&brdf);
    if (!analytic) return std::nullopt;
    std::map<std::string, double> out;
    for (std::size_t i = 0; i < analytic->model().size(); ++i) out[analytic->model().name(i)] = analytic->params()[i];
    return out;
}

}  // namespace

void bind_brdf(py::module_& m) {
    m.def("simd", &simd_name,
          "the instruction set Brdf's batch calls run with on this CPU: 'avx512', 'avx2' or 'sse2' (chosen at import)");
    py::class_<Brdf, BrdfPtr>(m, "Brdf", "A measured or compressed BRDF (brdf.h: normal +z, wi and wo pointing away)")
        .def("eval", &eval<false>, py::arg("wi"), py::arg("wo"),
             "f_r (1/sr, no cosine) at direction pairs: wi, wo of shape (N, 3) -> (N, 3) float64")
        .def("eval_cos", &eval<true>, py::arg("wi"), py::arg("wo"), "f_r·cosθi at direction pairs -> (N, 3) float64")
        .def("pdf", &pdf, py::arg("wo"), py::arg("wi"), "density of sample(wo, ·) at wi per unit solid angle -> (N,)")
        .def("sample", &sample, py::arg("wo"), py::arg("u"),
             "draws wi for each wo from u in [0, 1)^2 of shape (N, 2) (ValueError naming a row outside it) -> (wi (N, 3), pdf (N,), weight (N, 3)); "
             "weight = f·cosθi/pdf, failed samples have pdf 0 and weight 0")
        .def_property_readonly("channels", &Brdf::channels, "1 (monochrome, repeated in r, g, b) or 3")
        .def_property_readonly("nbytes", &Brdf::nbytes, "exact size of the stored parameters in bytes")
        .def("describe", &Brdf::describe, "one line saying what this is")
        .def_property_readonly("table", &table_view, "a table's values (θh, θd, φd, 3) float32, NaN where invalid; None otherwise")
        .def_property_readonly("parameters", &parameters, "an analytic model's parameters by name; None otherwise")
        .def("parts", &brdf_parts,
             "the representation's stored arrays and parameters as a dict ('kind': tabular, compact, factored, pca "
             "or analytic), read-only; None for kinds without parts (RGL files, scattered measurements)")
        .def("sampler_parts", &sampler_parts,
             "the tables of the sampler sample() and pdf() use ('kind': compact, halfvector or lobes), built with "
             "the representation; None for kinds without them")
        .def("__repr__", [](const Brdf& b) { return "<brdfz.Brdf " + b.describe() + ">"; });
}

}  // namespace brdfz::python
