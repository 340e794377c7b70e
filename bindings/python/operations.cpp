// Module-level functions: load / save / convert, compress, fit, metrics, tabulate, albedo, validate. Each
// releases the GIL while the library works; long ones take a progress callable (module.h).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <filesystem>
#include <numbers>
#include <optional>
#include <variant>

#include "brdfz/albedo.h"
#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/registry.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "brdfz/validate.h"
#include "module.h"

namespace brdfz::python {
namespace {

using Path = std::filesystem::path;
using Resolution = std::optional<std::tuple<int, int, int>>;

BinPosition parse_bin_position(const std::string& name) {
    if (name == "centre") return BinPosition::Centre;
    if (name == "start") return BinPosition::Start;
    throw ValueError("bin_position must be 'centre' or 'start', not '" + name + "'");
}

NegativePolicy parse_negative(const std::string& name) {
    if (name == "clamp") return NegativePolicy::Clamp;
    if (name == "invalidate") return NegativePolicy::Invalidate;
    throw ValueError("negative must be 'clamp' or 'invalidate', not '" + name + "'");
}

GridSpec grid_of(const std::tuple<int, int, int>& res) {
    GridSpec g{std::get<0>(res), std::get<1>(res), std::get<2>(res), BinPosition::Centre};
    g.validate();
    return g;
}

LoadOptions load_options(const std::string& lookup, const std::string& bin_position) {
    LoadOptions o;
    o.lookup = parse_lookup(lookup);
    o.position = parse_bin_position(bin_position);
    return o;
}

BrdfPtr load_brdf(const Path& path, const std::string& format, const LoadOptions& options) {
    return reading(path, [&] {
        py::gil_scoped_release release;
        const std::string p = path.string();
        return BrdfPtr(format.empty() ? load(p, options).brdf : load_as(format, p, options).brdf);
    });
}

py::dict counts_dict(const ValidityCounts& c) {
    using namespace py::literals;
    return py::dict("valid"_a = c.valid, "negative"_a = c.negative, "nan"_a = c.nan, "inf"_a = c.inf,
                    "clamped"_a = c.clamped, "below_horizon"_a = c.below_horizon);
}

// save() with the GIL released, progress reported and Ctrl-C heard; the written bins' counts.
py::dict save_counts(const Brdf& brdf, const Path& path, SaveOptions o, py::object progress) {
    Interruptible work(std::move(progress));
    o.progress = work.progress();
    return counts_dict(work.run([&] { return save(brdf, path.string(), o); }));
}

py::list rgb_list(const Rgb& v) { return py::cast(std::vector<double>(v.begin(), v.end())); }

// A check as `brdfz validate --json` prints it: ok, tested, failed, and the worst offences with
// their values under the check's names for them.
py::dict check_dict(const ValidationCheck& c) {
    py::list worst;
    for (const ValidationOffence& o : c.worst) {
        py::dict w;
        w["theta_i_deg"] = o.theta_i_deg;
        w["theta_o_deg"] = o.theta_o_deg;
        w["dphi_deg"] = o.dphi_deg;
        w[py::str(c.f_name)] = rgb_list(o.f);
        if (!c.g_name.empty()) w[py::str(c.g_name)] = rgb_list(o.g);
        worst.append(w);
    }
    py::dict d;
    d["ok"] = c.ok();
    d["tested"] = c.tested;
    d["failed"] = c.failed;
    if (c.error) d["error"] = *c.error;
    d["worst"] = worst;
    return d;
}

// compress()'s result with the Brdf shared, as Python holds every Brdf.
struct Built {
    BrdfPtr brdf;
    std::string spec;
    double build_seconds;
    std::vector<std::string> notes;
};

// fit()'s result, the model shared as a Brdf.
struct Fitted {
    BrdfPtr brdf;
    FitReport report;
};

// What fit and metrics take as data: a Brdf, or a file (scattered measurements or a BRDF).
using Data = std::variant<BrdfPtr, MeasurementSet>;

Data data_of(const py::handle& obj) {
    if (py::isinstance<Brdf>(obj)) return obj.cast<BrdfPtr>();
    if (!py::isinstance<py::str>(obj) && !py::hasattr(obj, "__fspath__"))
        throw py::type_error("expected a brdfz.Brdf or a path, got " + py::str(py::type::of(obj)).cast<std::string>());
    const Path path = obj.cast<Path>();
    return reading(path, [&]() -> Data {
        py::gil_scoped_release release;
        const std::string p = path.string();
        if (holds_measurements(p)) return load_measurements(p).set;
        return BrdfPtr(load(p).brdf);
    });
}

py::dict per_channel_dict(const PerChannel& c) {
    using namespace py::literals;
    return py::dict("r"_a = c.r, "g"_a = c.g, "b"_a = c.b, "mean"_a = c.mean);
}

using Rows = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An (N, 3) float64 array (converted when given otherwise); ValueError naming it for any other shape.
Rows rows3(const py::handle& obj, const char* name) {
    Rows a = Rows::ensure(obj);
    if (!a || a.ndim() != 2 || a.shape(1) != 3) {
        PyErr_Clear();
        throw ValueError(std::string(name) + ": expected an array of shape (N, 3)");
    }
    return a;
}

template <typename T>
Rows to_rows(const std::vector<T>& v) {
    Rows a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
    static_assert(sizeof(T) == 3 * sizeof(double));
    if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
    return a;
}

}  // namespace

MetricOptions metric_options(double max_theta, int threads, const std::string& over, std::size_t directions,
                             std::uint64_t seed) {
    return {.max_theta_deg = max_theta, .threads = threads, .over = parse_over(over), .directions = directions, .seed = seed};
}

void bind_operations(py::module_& m) {
    m.def("load", [](const Path& path, const std::string& lookup, const std::string& bin_position,
                     const std::string& format) { return load_brdf(path, format, load_options(lookup, bin_position)); },
          py::arg("path"), py::kw_only(), py::arg("lookup") = "linear", py::arg("bin_position") = "centre",
          py::arg("format") = "", "a BRDF file (.binary, .bsdf, .brdfz, .exr, .json; format overrides the extension)");

    m.def("load_measurements", [](const Path& path) {
              const MeasurementSet set = reading(path, [&] {
                  py::gil_scoped_release release;
                  return load_measurements(path.string()).set;
              });
              std::vector<Vec3> wi, wo;
              std::vector<Rgb> f;
              for (const Measurement& s : set.samples) {
                  wi.push_back(s.wi);
                  wo.push_back(s.wo);
                  f.push_back(s.f);
              }
              py::dict d;
              d["wi"] = to_rows(wi);
              d["wo"] = to_rows(wo);
              d["f"] = to_rows(f);
              d["channels"] = set.channels;
              d["source"] = set.source;
              return d;
          },
          py::arg("path"),
          "scattered measurements (Cornell .brdf, ALTA .dat): {'wi', 'wo' (N, 3) unit directions, 'f' (N, 3) f_r, "
          "'channels', 'source'}; UnsupportedError for a file holding a BRDF (load it)");
    m.def("save", [](const BrdfPtr& brdf, const Path& path, const Resolution& res, const std::string& format,
                     int threads, py::object progress, const std::string& build_spec, const std::optional<Path>& source,
                     const py::object& source_metrics) {
              SaveOptions o;
              if (res) o.grid = grid_of(*res);
              o.format = format;
              o.threads = threads;
              o.build_spec = build_spec;
              if (source) {
                  o.source = source->string();
                  o.source_format = detect_format(o.source);
              }
              // An object, not std::optional<Metrics>: Metrics is bound below, after this signature is made.
              if (!source_metrics.is_none()) o.source_metrics = source_metrics.cast<Metrics>();
              return save_counts(*brdf, path, o, std::move(progress));
          },
          py::arg("brdf").none(false), py::arg("path"), py::kw_only(), py::arg("res") = py::none(), py::arg("format") = "",
          py::arg("threads") = 0, py::arg("progress") = py::none(), py::arg("build_spec") = "",
          py::arg("source") = py::none(), py::arg("source_metrics") = py::none(),
          "writes atomically (format from the extension unless given); returns the written bins' counts. .brdfz "
          "keeps provenance: build_spec (the compress() spec), source (the file it came from: name, format and "
          "SHA-256) and source_metrics (its metrics against that file)");

    m.def("container_metadata", [](const Path& path) {
              const container::Metadata meta = reading(path, [&] {
                  py::gil_scoped_release release;
                  return container::read_metadata(path.string());
              });
              py::dict source, achieved, d;
              source["file"] = meta.source.file;
              source["format"] = meta.source.format;
              source["sha256"] = meta.source.sha256;
              achieved["lossless"] = meta.achieved.lossless;
              achieved["nbytes"] = meta.achieved.nbytes;
              achieved["metrics"] = meta.achieved.metrics ? py::cast(*meta.achieved.metrics) : py::none();
              d["version"] = meta.version;
              d["library_version"] = meta.library_version;
              d["created"] = meta.created;
              d["source"] = source;
              d["representation"] = meta.representation;
              d["spec"] = meta.spec;
              d["build_spec"] = meta.build_spec;
              d["achieved"] = achieved;
              return d;
          },
          py::arg("path"),
          "a .brdfz file's provenance without reading its arrays: {'version', 'library_version', 'created', "
          "'source' {'file', 'format', 'sha256'}, 'representation', 'spec', 'build_spec', 'achieved' {'lossless', "
          "'nbytes', 'metrics' (against the source, or None)}}");

    m.def("convert", [](const Path& src, const Path& dst, const Resolution& res, const std::string& src_format,
                        const std::string& dst_format, const std::string& lookup, const std::string& bin_position,
                        int threads, py::object progress) {
              ConvertOptions o;
              o.from = src_format;
              o.load = load_options(lookup, bin_position);
              if (res) o.save.grid = grid_of(*res);
              o.save.format = dst_format;
              o.save.threads = threads;
              Interruptible work(std::move(progress));
              o.save.progress = work.progress();
              return counts_dict(reading(src, [&] { return work.run([&] { return convert(src.string(), dst.string(), o); }); }));
          },
          py::arg("src"), py::arg("dst"), py::kw_only(), py::arg("res") = py::none(), py::arg("src_format") = "",
          py::arg("dst_format") = "", py::arg("lookup") = "linear", py::arg("bin_position") = "centre",
          py::arg("threads") = 0, py::arg("progress") = py::none(), "as `brdfz convert SRC DST`; returns the written bins' counts");

    py::class_<Built>(m, "Compressed", "what compress() built and what it achieved")
        .def_readonly("brdf", &Built::brdf)
        .def_readonly("spec", &Built::spec, "canonical spec text")
        .def_readonly("build_seconds", &Built::build_seconds, "wall time of the build")
        .def_readonly("notes", &Built::notes, "what the builder wants the user to know (fit status, clamping)")
        .def("__repr__", [](const Built& c) {
            return "<brdfz.Compressed " + c.spec + ": " + c.brdf->describe() + ", " + std::to_string(c.brdf->nbytes()) + " bytes>";
        });
    m.def("compress", [](const BrdfPtr& brdf, const std::string& spec, int threads, py::object progress) {
              CompressOptions o = with_file_access({});
              o.threads = threads;
              Interruptible work(std::move(progress));
              o.progress = work.progress();
              Compressed c = work.run([&] { return compress(*brdf, spec, o); });
              return Built{BrdfPtr(std::move(c.brdf)), c.spec, c.build_seconds, c.notes};
          },
          py::arg("brdf").none(false), py::arg("spec"), py::kw_only(), py::arg("threads") = 0, py::arg("progress") = py::none(),
          "builds the representation SPEC names (as `brdfz compress`)");
    m.def("compress_kinds", &compress_kinds);
    m.def("representations", [] {
              py::list out;
              for (const ReprKind& k : representation_kinds()) {
                  py::list keys;
                  for (const SpecKey& key : k.keys)
                      keys.append(py::dict(py::arg("name") = key.name, py::arg("default") = key.default_value,
                                           py::arg("help") = key.help));
                  out.append(py::dict(py::arg("kind") = k.name, py::arg("summary") = k.summary,
                                      py::arg("positional") = k.positional,
                                      py::arg("measurements") = k.build_measurements != nullptr, py::arg("keys") = keys));
              }
              return out;
          },
          "the representation kinds compress() builds, as `brdfz representations --json` lists them");
    m.def("formats", [] {
              py::list out;
              for (const Format& f : all_formats())
                  out.append(py::dict(py::arg("name") = f.name, py::arg("description") = f.description,
                                      py::arg("extensions") = f.extensions,
                                      py::arg("reads") = f.read ? "brdf" : f.read_measurements ? "measurements" : "",
                                      py::arg("writes") = f.write != nullptr));
              return out;
          },
          "the file formats, as `brdfz formats --json` lists them");

    py::class_<PerChannel>(m, "ChannelMetrics", "one metric per channel and their mean")
        .def_readonly("r", &PerChannel::r)
        .def_readonly("g", &PerChannel::g)
        .def_readonly("b", &PerChannel::b)
        .def_readonly("mean", &PerChannel::mean)
        .def("to_dict", &per_channel_dict)
        .def("__repr__", [](const PerChannel& c) {
            return py::str("ChannelMetrics(r={:.6g}, g={:.6g}, b={:.6g}, mean={:.6g})").format(c.r, c.g, c.b, c.mean);
        });
    py::class_<Metrics>(m, "Metrics", "error metrics of an approximation against a reference (metrics.h)")
        .def_readonly("cos_rmse", &Metrics::cos_rmse)
        .def_readonly("cos_rmse_rel", &Metrics::cos_rmse_rel)
        .def_readonly("log_rmse", &Metrics::log_rmse)
        .def_readonly("cbrt_rmse", &Metrics::cbrt_rmse)
        .def_readonly("samples", &Metrics::samples, "bins (or measurements) compared")
        .def_readonly("negatives", &Metrics::negatives, "channel values below 0 (either BRDF), taken as 0 by every metric")
        .def("to_dict", [](const Metrics& x) {
            py::dict d;
            d["cos_rmse"] = per_channel_dict(x.cos_rmse);
            d["cos_rmse_rel"] = per_channel_dict(x.cos_rmse_rel);
            d["log_rmse"] = per_channel_dict(x.log_rmse);
            d["cbrt_rmse"] = per_channel_dict(x.cbrt_rmse);
            d["samples"] = x.samples;
            d["negatives"] = x.negatives;
            return d;
        })
        .def("__repr__", [](const Metrics& x) {
            return py::str("Metrics(cos_rmse={:.6g}, cos_rmse_rel={:.6g}, log_rmse={:.6g}, cbrt_rmse={:.6g}, samples={})")
                .format(x.cos_rmse.mean, x.cos_rmse_rel.mean, x.log_rmse.mean, x.cbrt_rmse.mean, x.samples);
        });
    m.def("metrics", [](const py::object& reference, const BrdfPtr& approx, double max_theta, int threads,
                        const std::string& over, std::size_t directions, std::uint64_t seed) {
              const MetricOptions o = metric_options(max_theta, threads, over, directions, seed);
              const Data ref = data_of(reference);
              return Interruptible().run([&] {
                  if (const auto* set = std::get_if<MeasurementSet>(&ref)) return compare(*set, *approx, o);
                  return compare(*std::get<BrdfPtr>(ref), *approx, o);
              });
          },
          py::arg("reference"), py::arg("approx").none(false), py::kw_only(), py::arg("max_theta") = 80.0, py::arg("threads") = 0,
          py::arg("over") = "grid", py::arg("directions") = MetricOptions{}.directions, py::arg("seed") = MetricOptions{}.seed,
          "metrics of approx against reference (a Brdf, or a file: a BRDF or Cornell/ALTA measurements)");
    m.def("reciprocity_error", [](const BrdfPtr& brdf, double max_theta, int threads, std::size_t directions,
                                  std::uint64_t seed) {
              const MetricOptions o = metric_options(max_theta, threads, "directions", directions, seed);
              return Interruptible().run([&] { return reciprocity_error(*brdf, o); });
          },
          py::arg("brdf").none(false), py::kw_only(), py::arg("max_theta") = 80.0, py::arg("threads") = 0,
          py::arg("directions") = MetricOptions{}.directions, py::arg("seed") = MetricOptions{}.seed,
          "metrics of f(wo, wi) against f(wi, wo) over direction pairs (cos_rmse_rel.mean: the reciprocity error)");
    m.def("metric_samples", [](const BrdfPtr& reference, double max_theta, int threads, const std::string& over,
                               std::size_t directions, std::uint64_t seed) {
              const MetricOptions o = metric_options(max_theta, threads, over, directions, seed);
              const MetricSamples s = Interruptible().run([&] { return metric_samples(*reference, o); });
              return py::make_tuple(to_rows(s.wi), to_rows(s.wo), to_rows(s.reference));
          },
          py::arg("reference").none(false), py::kw_only(), py::arg("max_theta") = 80.0, py::arg("threads") = 0,
          py::arg("over") = "grid", py::arg("directions") = MetricOptions{}.directions, py::arg("seed") = MetricOptions{}.seed,
          "(wi, wo, f_reference): the samples metrics() takes against reference");
    m.def("metrics_at", [](const py::object& wi_obj, const py::object& ref_obj, const py::object& app_obj) {
              const Rows wi = rows3(wi_obj, "wi"), ref = rows3(ref_obj, "reference"), app = rows3(app_obj, "approx");
              const auto n = static_cast<std::size_t>(wi.shape(0));
              if (static_cast<std::size_t>(ref.shape(0)) != n || static_cast<std::size_t>(app.shape(0)) != n)
                  throw ValueError("metrics_at: wi, reference and approx have different lengths");
              std::vector<Vec3> w(n);
              for (std::size_t k = 0; k < n; ++k) w[k] = {wi.at(k, 0), wi.at(k, 1), wi.at(k, 2)};
              const auto* r = reinterpret_cast<const Rgb*>(ref.data());
              const auto* a = reinterpret_cast<const Rgb*>(app.data());
              return compare_values(w, std::span<const Rgb>(r, n), std::span<const Rgb>(a, n));
          },
          py::arg("wi"), py::arg("reference"), py::arg("approx"),
          "the metrics of approx against reference values (N, 3) at pairs whose incident directions are wi");

    py::class_<FitReport>(m, "FitReport", "how a fit went (fit/fit.h)")
        .def_property_readonly("status", [](const FitReport& r) { return fit_status_name(r.status); },
                               "converged, hit_bounds, no_convergence or insufficient_data")
        .def_readonly("message", &FitReport::message)
        .def_readonly("warnings", &FitReport::warnings)
        .def_readonly("at_bounds", &FitReport::at_bounds)
        .def_readonly("model", &FitReport::model)
        .def_property_readonly("loss", [](const FitReport& r) { return fit_loss_name(r.loss); })
        .def_readonly("samples", &FitReport::samples)
        .def_readonly("excluded_cutoff", &FitReport::excluded_cutoff)
        .def_readonly("excluded_invalid", &FitReport::excluded_invalid)
        .def_readonly("grid_bins", &FitReport::grid_bins)
        .def_readonly("channel_cost", &FitReport::channel_cost)
        .def_readonly("initial_cost", &FitReport::initial_cost)
        .def_readonly("final_cost", &FitReport::final_cost)
        .def_readonly("iterations", &FitReport::iterations)
        .def_readonly("total_iterations", &FitReport::total_iterations)
        .def_readonly("termination", &FitReport::termination)
        .def_readonly("seconds", &FitReport::seconds)
        .def_readonly("starts", &FitReport::starts)
        .def_readonly("best_start", &FitReport::best_start)
        .def_readonly("start_costs", &FitReport::start_costs)
        .def_readonly("unexplained", &FitReport::unexplained)
        .def_readonly("poor_fit", &FitReport::poor_fit,
                      "whatever the status, the model misses the data (unexplained > 0.25 or cos_rmse_rel > 0.5)")
        .def_readonly("metrics", &FitReport::metrics, "the model against the input, or None")
        .def("__repr__", [](const FitReport& r) {
            return "<brdfz.FitReport " + r.model + ": " + fit_status_name(r.status) + (r.poor_fit ? " but poor fit" : "") +
                   ", " + r.message + ">";
        });
    py::class_<Fitted>(m, "FitResult", "a fitted model and its report")
        .def_readonly("brdf", &Fitted::brdf)
        .def_readonly("report", &Fitted::report)
        .def("__repr__", [](const Fitted& f) { return "<brdfz.FitResult " + f.brdf->describe() + ": " + fit_status_name(f.report.status) + ">"; });
    m.def("fit", [](const py::object& source, const std::string& model, const std::string& loss, int starts,
                    std::uint64_t seed, const std::string& robust, double robust_scale, double max_theta,
                    std::size_t samples, double max_seconds, int threads, py::object progress) {
              FitOptions o;
              o.loss = parse_fit_loss(loss);
              o.starts = starts;
              o.seed = seed;
              o.robust = parse_robust_loss(robust);
              o.robust_scale = robust_scale;
              o.max_theta_deg = max_theta;
              o.sampling.max_samples = samples;
              o.max_seconds = max_seconds;
              o.threads = threads;
              Model::parse(model);  // a bad model string fails before any loading
              const Data data = data_of(source);
              Interruptible work(std::move(progress));
              o.progress = work.progress();
              FitResult r = work.run([&] {
                  if (const auto* set = std::get_if<MeasurementSet>(&data)) return fit(*set, model, o);
                  return fit(*std::get<BrdfPtr>(data), model, o);
              });
              return Fitted{std::make_shared<AnalyticBrdf>(std::move(r.model)), std::move(r.report)};
          },
          py::arg("source"), py::arg("model"), py::kw_only(), py::arg("loss") = "log", py::arg("starts") = 8,
          py::arg("seed") = 1, py::arg("robust") = "none", py::arg("robust_scale") = 0.1, py::arg("max_theta") = 80.0,
          py::arg("samples") = 20000, py::arg("max_seconds") = 60.0, py::arg("threads") = 0,
          py::arg("progress") = py::none(),
          "fits an analytic model (e.g. 'lambert+ggx') to a Brdf or a file, as `brdfz fit`");

    m.def("tabulate", [](const BrdfPtr& brdf, const std::tuple<int, int, int>& res, const std::string& lookup,
                         const std::string& negative, const std::string& symmetry, int threads, py::object progress) {
              TabulateOptions o;
              o.grid = grid_of(res);
              o.grid.symmetry = parse_symmetry(symmetry);
              o.negative = parse_negative(negative);
              o.threads = threads;
              const Lookup l = parse_lookup(lookup);
              Interruptible work(std::move(progress));
              o.progress = work.progress();
              return work.run([&] { return BrdfPtr(std::make_shared<TabularBrdf>(tabulate(*brdf, o).table, l)); });
          },
          py::arg("brdf").none(false), py::arg("res") = std::make_tuple(90, 90, 180), py::kw_only(), py::arg("lookup") = "linear",
          py::arg("negative") = "clamp", py::arg("symmetry") = "reciprocal", py::arg("threads") = 0,
          py::arg("progress") = py::none(),
          "the Brdf evaluated on a (θh, θd, φd) Rusinkiewicz grid at bin centres, as a table (symmetry: table.h)");

    m.def("albedo", [](const BrdfPtr& brdf, const py::array_t<double, py::array::forcecast>& theta_o) {
              const py::ssize_t n = theta_o.size();
              const double* t = theta_o.data();
              for (py::ssize_t k = 0; k < n; ++k)
                  if (!(t[k] >= 0.0 && t[k] < std::numbers::pi / 2))
                      throw ValueError("albedo: theta_o must lie in [0, pi/2) radians, got " + std::to_string(t[k]));
              std::vector<py::ssize_t> shape(theta_o.shape(), theta_o.shape() + theta_o.ndim());
              shape.push_back(3);
              py::array_t<double> out(shape);
              double* rho = out.mutable_data();
              py::gil_scoped_release release;
              for (py::ssize_t k = 0; k < n; ++k) {
                  const Rgb a = directional_albedo(*brdf, t[k]);
                  for (int c = 0; c < 3; ++c) rho[3 * k + c] = a[c];
              }
              return out;
          },
          py::arg("brdf").none(false), py::arg("theta_o"),
          "directional albedo (quadrature, albedo.h) at θo in radians: shape of theta_o + (3,)");

    py::class_<ValidationCheck>(m, "ValidationCheck", "one plausibility check (validate.h)")
        .def_readonly("name", &ValidationCheck::name, "non-negativity, reciprocity or energy")
        .def_readonly("unit", &ValidationCheck::unit, "what was tested: bins, pairs or elevations")
        .def_readonly("tested", &ValidationCheck::tested)
        .def_readonly("failed", &ValidationCheck::failed)
        .def_readonly("error", &ValidationCheck::error,
                      "reciprocity: the reciprocity error (cos_rmse_rel of f(wo, wi) against f(wi, wo) over directions); "
                      "None for the other checks")
        .def_property_readonly("ok", &ValidationCheck::ok)
        .def_property_readonly("worst", [](const ValidationCheck& c) { return py::list(check_dict(c)["worst"]); },
                               "the worst offences, worst first: angles in degrees and the values involved")
        .def("to_dict", &check_dict)
        .def("__repr__", [](const ValidationCheck& c) {
            return "<brdfz.ValidationCheck " + c.name + ": " + (c.ok() ? "ok" : "FAIL") + ", " + std::to_string(c.failed) +
                   " of " + std::to_string(c.tested) + " " + c.unit + " fail>";
        });
    py::class_<ValidationReport>(m, "ValidationReport", "the checks of validate(), in order")
        .def_readonly("checks", &ValidationReport::checks)
        .def_property_readonly("ok", &ValidationReport::ok)
        .def("__getitem__", [](const ValidationReport& r, const std::string& name) {
            for (const ValidationCheck& c : r.checks)
                if (c.name == name) return c;
            throw py::key_error(name);
        })
        .def("to_dict", [](const ValidationReport& r) {
            py::dict d;
            d["ok"] = r.ok();
            for (const ValidationCheck& c : r.checks) d[py::str(c.name)] = check_dict(c);
            return d;
        }, "as `brdfz validate --json` prints it, without the file name")
        .def("__repr__", [](const ValidationReport& r) {
            return "<brdfz.ValidationReport " + (r.ok() ? std::string("ok") : "failed: " + r.failed_names()) + ">";
        });
    m.def("validate", [](const BrdfPtr& brdf, const std::tuple<int, int, int>& res, const std::vector<double>& theta,
                         double rtol, double atol, double albedo_tol) {
              ValidateOptions o;
              o.grid = grid_of(res);
              o.theta_deg = theta;
              o.rtol = rtol;
              o.atol = atol;
              o.albedo_tol = albedo_tol;
              return Interruptible().run([&] { return validate(*brdf, o); });
          },
          py::arg("brdf").none(false), py::kw_only(), py::arg("res") = std::make_tuple(90, 90, 180),
          py::arg("theta") = ValidateOptions{}.theta_deg, py::arg("rtol") = 0.05, py::arg("atol") = 1e-3,
          py::arg("albedo_tol") = 0.01,
          "non-negativity (a table's values, else f on the res grid), reciprocity (rtol, atol in 1/sr) and "
          "energy (reflectance <= 1 + albedo_tol at the elevations theta, degrees), as `brdfz validate`");
}

}  // namespace brdfz::python
