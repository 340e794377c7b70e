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

#include "brdfz/coords.h"
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

std::string shape_text(const py::array& a) {
    std::string shape;
    for (py::ssize_t k = 0; k < a.ndim(); ++k) shape += (k ? ", " : "") + std::to_string(a.shape(k));
    return "(" + shape + (a.ndim() == 1 ? ",)" : ")");
}

// An argument as an array of shape (..., cols): numpy arrays of directions as they are (float32 or
// float64, as as_rows checks), lists and tuples read as float64; with cols 0, any real numbers (angles)
// as float64. ValueError naming it otherwise.
py::array as_array(const ArrayArg& arg, const char* name, py::ssize_t cols) {
    const std::string expected = cols ? "shape (..., " + std::to_string(cols) + ")" : "real numbers";
    py::array array;
    if (cols && py::isinstance<py::array>(arg.obj)) {
        array = py::reinterpret_borrow<py::array>(arg.obj);
        const py::dtype dtype = array.dtype();
        if (dtype.kind() != 'f' || (dtype.itemsize() != 4 && dtype.itemsize() != 8))
            throw ValueError(std::string(name) + ": expected float32 or float64, got " + py::str(dtype).cast<std::string>());
    } else {
        try {
            array = py::module_::import("numpy").attr("asarray")(arg.obj, py::arg("dtype") = "float64");
        } catch (const py::error_already_set&) {
            throw ValueError(std::string(name) + ": expected a numpy array, list or tuple of " + expected);
        }
    }
    if (cols && (array.ndim() == 0 || array.shape(array.ndim() - 1) != cols))
        throw ValueError(std::string(name) + ": expected " + expected + ", got " + shape_text(array));
    return array;
}

// Arguments broadcast against each other over their leading dimensions (numpy's rules; the last
// `cols[k]` trailing entries of each are its own) as rows, and the broadcast leading shape.
struct Broadcast {
    std::vector<Rows> rows;
    py::tuple shape;
};

Broadcast broadcast(const std::vector<py::array>& arrays, const std::vector<const char*>& names,
                    const std::vector<py::ssize_t>& cols) {
    Broadcast out;
    // Rows of equal length, the common case, as they are: numpy's broadcasting costs several times a
    // small batch's evaluation.
    const bool rows = std::all_of(arrays.begin(), arrays.end(), [&](const py::array& a) {
        return cols[&a - arrays.data()] && a.ndim() == 2 && a.shape(0) == arrays[0].shape(0);
    });
    if (rows) {
        for (std::size_t k = 0; k < arrays.size(); ++k) out.rows.push_back(as_rows(ArrayArg{arrays[k]}, names[k], cols[k]));
        out.shape = py::make_tuple(arrays[0].shape(0));
        return out;
    }
    const py::module_ np = py::module_::import("numpy");
    py::list leading;
    for (std::size_t k = 0; k < arrays.size(); ++k) {
        const py::tuple shape = arrays[k].attr("shape");
        leading.append(shape[py::slice(0, shape.size() - (cols[k] ? 1 : 0), 1)]);
    }
    try {
        out.shape = np.attr("broadcast_shapes")(*leading).cast<py::tuple>();
    } catch (const py::error_already_set&) {
        // The message the calls gave before they broadcast, for the case it covers.
        if (arrays.size() == 2 && arrays[0].ndim() == 2 && arrays[1].ndim() == 2)
            throw ValueError(std::string(names[0]) + " and " + names[1] + " have different lengths (" +
                             std::to_string(arrays[0].shape(0)) + " and " + std::to_string(arrays[1].shape(0)) + ")");
        std::string text;
        for (std::size_t k = 0; k < arrays.size(); ++k)
            text += std::string(k ? (k + 1 == arrays.size() ? " and " : ", ") : "") + names[k] + " " + shape_text(arrays[k]);
        throw ValueError("shapes do not broadcast: " + text);
    }
    py::ssize_t n = 1;
    for (const auto d : out.shape) n *= d.cast<py::ssize_t>();
    for (std::size_t k = 0; k < arrays.size(); ++k) {
        const py::tuple full = cols[k] ? py::tuple(out.shape + py::make_tuple(cols[k])) : out.shape;
        // reshape copies only when the broadcast view cannot be flattened in place.
        const py::array flat = np.attr("broadcast_to")(arrays[k], full).attr("reshape")(n, cols[k] ? cols[k] : 1);
        out.rows.push_back(as_rows(ArrayArg{flat}, names[k], cols[k] ? cols[k] : 1));
    }
    return out;
}

// A result of rows reshaped to the broadcast leading shape (and its trailing `cols`, unless 1); 0-d
// for one pair's pdf.
Array shaped(const Array& result, const py::tuple& shape, py::ssize_t cols) {
    if (shape.size() == 1) return result;  // rows in, rows out
    const py::tuple full = cols > 1 ? py::tuple(shape + py::make_tuple(cols)) : shape;
    return result.attr("reshape")(full).cast<Array>();
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
    const Broadcast b = broadcast({as_array(wi_obj, "wi", 3), as_array(wo_obj, "wo", 3)}, {"wi", "wo"}, {3, 3});
    const Rows &wi = b.rows[0], &wo = b.rows[1];
    Array out = new_rows(wi.size(), 3);
    auto* f = reinterpret_cast<Rgb*>(out.mutable_data());
    for_blocks(wi, "wi", wo, "wo", [&](std::size_t begin, std::span<const Vec3> wi_k, std::span<const Vec3> wo_k) {
        const std::span<Rgb> f_k(f + begin, wi_k.size());
        if constexpr (Cosine)
            brdf.eval_cos(wi_k, wo_k, f_k);
        else
            brdf.eval(wi_k, wo_k, f_k);
    });
    return shaped(out, b.shape, 3);
}

Array pdf(const Brdf& brdf, const ArrayArg& wo_obj, const ArrayArg& wi_obj) {
    const Broadcast b = broadcast({as_array(wo_obj, "wo", 3), as_array(wi_obj, "wi", 3)}, {"wo", "wi"}, {3, 3});
    const Rows &wo = b.rows[0], &wi = b.rows[1];
    Array out = new_rows(wo.size(), 1);
    double* p = out.mutable_data();
    for_blocks(wo, "wo", wi, "wi", [&](std::size_t begin, std::span<const Vec3> wo_k, std::span<const Vec3> wi_k) {
        brdf.pdf(wo_k, wi_k, std::span<double>(p + begin, wo_k.size()));
    });
    return shaped(out, b.shape, 1);
}

// Rusinkiewicz angles (coords.h) of direction pairs, broadcast: (θh, φh, θd, φd), each of the
// leading shape.
py::tuple half_diff(const ArrayArg& wi_obj, const ArrayArg& wo_obj) {
    const Broadcast b = broadcast({as_array(wi_obj, "wi", 3), as_array(wo_obj, "wo", 3)}, {"wi", "wo"}, {3, 3});
    const Rows &wi = b.rows[0], &wo = b.rows[1];
    std::array<Array, 4> out;
    for (auto& a : out) a = new_rows(wi.size(), 1);
    std::array<double*, 4> p;
    for (std::size_t k = 0; k < 4; ++k) p[k] = out[k].mutable_data();
    for_blocks(wi, "wi", wo, "wo", [&](std::size_t begin, std::span<const Vec3> wi_k, std::span<const Vec3> wo_k) {
        for (std::size_t k = 0; k < wi_k.size(); ++k) {
            const HalfDiff hd = to_half_diff(wi_k[k], wo_k[k]);
            p[0][begin + k] = hd.theta_h, p[1][begin + k] = hd.phi_h, p[2][begin + k] = hd.theta_d,
            p[3][begin + k] = hd.phi_d;
        }
    });
    return py::make_tuple(shaped(out[0], b.shape, 1), shaped(out[1], b.shape, 1), shaped(out[2], b.shape, 1),
                          shaped(out[3], b.shape, 1));
}

// Angle arrays broadcast against each other, as float64 rows; ValueError naming a non-finite one.
Broadcast angles(const std::vector<ArrayArg>& args, const std::vector<const char*>& names) {
    std::vector<py::array> arrays;
    for (std::size_t k = 0; k < args.size(); ++k) arrays.push_back(as_array(args[k], names[k], 0));
    Broadcast b = broadcast(arrays, names, std::vector<py::ssize_t>(args.size(), 0));
    for (std::size_t k = 0; k < args.size(); ++k) {
        const double* v = b.rows[k].data<double>();
        for (std::size_t i = 0; i < b.rows[k].size(); ++i)
            if (!std::isfinite(v[i]))
                throw ValueError(std::string(names[k]) + "[" + std::to_string(i) + "]: angle must be finite");
    }
    return b;
}

// Direction pairs (wi, wo) from Rusinkiewicz angles (coords.h), broadcast.
py::tuple pairs_from_half_diff(const ArrayArg& theta_h, const ArrayArg& theta_d, const ArrayArg& phi_d,
                               const ArrayArg& phi_h) {
    const Broadcast b = angles({theta_h, theta_d, phi_d, phi_h}, {"theta_h", "theta_d", "phi_d", "phi_h"});
    const std::size_t n = b.rows[0].size();
    Array wi = new_rows(n, 3), wo = new_rows(n, 3);
    auto *pi = reinterpret_cast<Vec3*>(wi.mutable_data()), *po = reinterpret_cast<Vec3*>(wo.mutable_data());
    static_assert(sizeof(Vec3) == 3 * sizeof(double));
    const double *th = b.rows[0].data<double>(), *td = b.rows[1].data<double>(), *pd = b.rows[2].data<double>(),
                 *ph = b.rows[3].data<double>();
    for (std::size_t k = 0; k < n; ++k) std::tie(pi[k], po[k]) = from_half_diff({th[k], ph[k], td[k], pd[k]});
    return py::make_tuple(shaped(wi, b.shape, 3), shaped(wo, b.shape, 3));
}

// Unit directions at polar angles theta from +z and azimuths phi from +x (frame.h), broadcast.
Array spherical(const ArrayArg& theta, const ArrayArg& phi) {
    const Broadcast b = angles({theta, phi}, {"theta", "phi"});
    const std::size_t n = b.rows[0].size();
    Array out = new_rows(n, 3);
    auto* d = reinterpret_cast<Vec3*>(out.mutable_data());
    const double *t = b.rows[0].data<double>(), *p = b.rows[1].data<double>();
    for (std::size_t k = 0; k < n; ++k) d[k] = spherical_direction(t[k], p[k]);
    return shaped(out, b.shape, 3);
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
    m.def("directions", &spherical, py::arg("theta"), py::arg("phi"),
          "unit directions at polar angles theta (from the normal +z) and azimuths phi (from +x), radians, "
          "broadcast -> (..., 3)");
    m.def("to_half_diff", &half_diff, py::arg("wi"), py::arg("wo"),
          "Rusinkiewicz angles of direction pairs (coords.h), broadcast as Brdf.eval -> (theta_h, phi_h, theta_d, "
          "phi_d), radians, each of the leading shape");
    m.def("from_half_diff", &pairs_from_half_diff, py::arg("theta_h"), py::arg("theta_d"), py::arg("phi_d"),
          py::arg("phi_h") = 0.0,
          "direction pairs (wi, wo) at Rusinkiewicz angles (radians, broadcast), each (..., 3); to_half_diff's inverse");
    m.def("simd", &simd_name,
          "the instruction set Brdf's batch calls run with on this CPU: 'avx512', 'avx2' or 'sse2' (x86-64, chosen at "
          "import), 'neon' (ARM64)");
    py::class_<Brdf, BrdfPtr>(m, "Brdf", "A measured or compressed BRDF (brdf.h: normal +z, wi and wo pointing away)")
        .def("eval", &eval<false>, py::arg("wi"), py::arg("wo"),
             "f_r (1/sr, no cosine) at direction pairs: wi, wo of shape (..., 3) (arrays, lists or tuples), broadcast "
             "over their leading dimensions -> (..., 3) float64 ((3,) for one pair)")
        .def("eval_cos", &eval<true>, py::arg("wi"), py::arg("wo"),
             "f_r·cosθi at direction pairs, broadcast as eval -> (..., 3) float64")
        .def("pdf", &pdf, py::arg("wo"), py::arg("wi"),
             "density of sample(wo, ·) at wi per unit solid angle, broadcast as eval -> (...) (a scalar for one pair)")
        .def("sample", &sample, py::arg("wo"), py::arg("u"),
             "draws wi for each wo from u in [0, 1)^2 of shape (N, 2) (ValueError naming a row outside it) -> (wi (N, 3), pdf (N,), weight (N, 3)); "
             "weight = f·cosθi/pdf, failed samples have pdf 0 and weight 0")
        .def_property_readonly("channels", &Brdf::channels, "1 (monochrome, repeated in r, g, b) or 3")
        .def_property_readonly("nbytes", &Brdf::nbytes, "exact size of the stored parameters in bytes")
        .def("describe", &Brdf::describe, "one line saying what this is")
        .def_property_readonly("measured_theta_max", &Brdf::measured_theta_max,
                               "the largest incident elevation (radians) up to which values are data, not "
                               "extrapolation: below π/2 for RGL files (their θi range), π/2 otherwise")
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
