// Measuring and choosing representations (brdfz/select.h): trial, select_representation, scenes and
// the benchmark's settings. Results are copied into plain structs holding the Brdf shared, as Python
// holds every Brdf (module.h); a rejected candidate keeps no Brdf, as in the library.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>

#include "brdfz/formats/io.h"
#include "brdfz/formats/scene_json.h"
#include "brdfz/select.h"
#include "module.h"

namespace brdfz::python {
namespace {

using Path = std::filesystem::path;

// What trial() measured, the Brdf shared (None for a rejected candidate).
struct TrialResult {
    BrdfPtr brdf;
    std::string spec, describe;
    std::size_t bytes = 0;
    Metrics metrics;
    double eval_rate = 0, build_seconds = 0;
    std::vector<std::string> notes;
};

struct CandidateResult : TrialResult {
    double error = 0;
    bool accepted = false;
    std::string reason;
};

struct SelectionResult {
    std::vector<CandidateResult> candidates;
    int chosen = -1;
    BrdfPtr brdf;  // the chosen candidate's, or None
};

// The measurements of a trial or candidate, without its Brdf.
TrialResult summary_of(const Trial& t) {
    return {nullptr, t.spec, t.describe, t.bytes, t.metrics, t.eval_rate, t.build_seconds, t.notes};
}

CandidateResult summary_of(const Candidate& c) {
    CandidateResult r;
    static_cast<TrialResult&>(r) = summary_of(c.trial);
    r.error = c.error;
    r.accepted = c.accepted;
    r.reason = c.reason;
    return r;
}

TrialOptions trial_options(bool measure_speed, const MetricOptions& metrics) {
    TrialOptions o;
    o.compress = with_file_access(o.compress);
    o.measure_speed = measure_speed;
    o.metrics = metrics;
    o.compress.threads = metrics.threads;
    return o;
}

}  // namespace

void bind_select(py::module_& m) {
    py::class_<TrialResult>(m, "Trial", "what one representation achieved against its source (select.h)")
        .def_readonly("brdf", &TrialResult::brdf, "the representation (None for a rejected candidate)")
        .def_readonly("spec", &TrialResult::spec, "canonical spec text")
        .def_readonly("describe", &TrialResult::describe)
        .def_readonly("bytes", &TrialResult::bytes, "Brdf.nbytes of the result")
        .def_readonly("metrics", &TrialResult::metrics, "the result against the source")
        .def_readonly("eval_rate", &TrialResult::eval_rate, "batch eval, pairs per second on one thread (0: not measured)")
        .def_readonly("build_seconds", &TrialResult::build_seconds)
        .def_readonly("notes", &TrialResult::notes, "from the builder (fit status, clamping)")
        .def("__repr__", [](const TrialResult& t) {
            return "<brdfz.Trial " + t.spec + ": " + std::to_string(t.bytes) + " bytes, cos_rmse_rel " +
                   std::to_string(t.metrics.cos_rmse_rel.mean) + ">";
        });
    py::class_<CandidateResult, TrialResult>(m, "Candidate", "one candidate of a selection and why it was kept or not")
        .def_readonly("error", &CandidateResult::error, "in the selection's metric; NaN when the candidate failed")
        .def_readonly("accepted", &CandidateResult::accepted)
        .def_readonly("reason", &CandidateResult::reason, "why it was rejected, or 'meets the budget'")
        .def("__repr__", [](const CandidateResult& c) {
            return "<brdfz.Candidate " + c.spec + ": " + std::to_string(c.bytes) + " bytes, " + c.reason + ">";
        });
    py::class_<SelectionResult>(m, "Selection", "every candidate tried, cheapest first, and the one chosen")
        .def_readonly("candidates", &SelectionResult::candidates)
        .def_readonly("chosen", &SelectionResult::chosen, "index into candidates; -1 when none met the budget")
        .def_readonly("brdf", &SelectionResult::brdf, "the chosen representation, or None")
        .def("__repr__", [](const SelectionResult& s) {
            return "<brdfz.Selection " + std::to_string(s.candidates.size()) + " tried, chose " +
                   (s.chosen < 0 ? std::string("none") : s.candidates[static_cast<std::size_t>(s.chosen)].spec) + ">";
        });

    py::class_<Scene>(m, "Scene", "the direction pairs a scene evaluates and their weights (scene.h)")
        .def_readonly("name", &Scene::name)
        .def_readonly("views", &Scene::views, "views (pixels)")
        .def_property_readonly("samples", [](const Scene& s) { return s.samples.size(); }, "direction pairs");
    m.def("read_scene", [](const Path& path) {
              return reading(path, [&] {
                  py::gil_scoped_release release;
                  return scene_json::load(path.string());
              });
          },
          py::arg("path"), "a scene file (docs/scene-json.md), its samples drawn");

    m.def("trial", [](const BrdfPtr& brdf, const std::string& spec, bool measure_speed, double max_theta, int threads,
                      const std::string& over, std::size_t directions, std::uint64_t seed, py::object progress) {
              TrialOptions o = trial_options(measure_speed, metric_options(max_theta, threads, over, directions, seed));
              Interruptible work(std::move(progress));
              o.compress.progress = work.progress();
              Trial t = work.run([&] { return trial(*brdf, spec, o); });
              TrialResult r = summary_of(t);
              r.brdf = BrdfPtr(std::move(t.brdf));
              return r;
          },
          py::arg("brdf").none(false), py::arg("spec"), py::kw_only(), py::arg("measure_speed") = true, py::arg("max_theta") = 80.0,
          py::arg("threads") = 0, py::arg("over") = "grid", py::arg("directions") = MetricOptions{}.directions,
          py::arg("seed") = MetricOptions{}.seed, py::arg("progress") = py::none(),
          "compress(brdf, spec) and measure it: bytes, metrics, eval speed, build time");

    m.def("select_representation",
          [](const BrdfPtr& brdf, const std::optional<double>& max_error, const std::optional<std::uint64_t>& max_bytes,
             const std::string& metric, const std::optional<Scene>& scene, const std::vector<std::string>& candidates,
             bool measure_speed, int threads, const std::string& over, std::size_t directions, std::uint64_t seed,
             py::object on_candidate) {
              SelectOptions o;
              o.max_error = max_error;
              o.max_bytes = max_bytes;
              o.metric = parse_scene_metric(metric);
              o.scene = scene;
              o.candidates = candidates;
              o.trial = trial_options(measure_speed, metric_options(80.0, threads, over, directions, seed));
              // The callable runs on this thread, with the GIL taken back for the call; its exception
              // ends the selection there.
              Interruptible work;
              std::size_t index = 0;
              const std::size_t total = candidates.empty() ? default_candidates().size() : candidates.size();
              if (!on_candidate.is_none())
                  o.on_candidate = [&](const Candidate& c) {
                      work.call([&] { on_candidate(summary_of(c), index++, total); });
                  };
              Selection s = work.run([&] { return select_representation(*brdf, o); });
              SelectionResult out;
              out.chosen = s.chosen;
              for (Candidate& c : s.tried) {
                  out.candidates.push_back(summary_of(c));
                  out.candidates.back().brdf = BrdfPtr(std::move(c.trial.brdf));
              }
              if (out.chosen >= 0) out.brdf = out.candidates[static_cast<std::size_t>(out.chosen)].brdf;
              return out;
          },
          py::arg("brdf").none(false), py::arg("max_error") = py::none(), py::kw_only(), py::arg("max_bytes") = py::none(),
          py::arg("metric") = "log", py::arg("scene") = py::none(),
          py::arg("candidates") = std::vector<std::string>{}, py::arg("measure_speed") = true, py::arg("threads") = 0,
          py::arg("over") = "directions", py::arg("directions") = MetricOptions{}.directions,
          py::arg("seed") = MetricOptions{}.seed, py::arg("on_candidate") = py::none(),
          "by budget (select.h): the smallest candidate within max_error, the most accurate within max_bytes, or the "
          "smallest within both; on_candidate(candidate, index, total) after each");

    m.def("benchmark_specs", &benchmark_specs, "the settings the compression benchmark sweeps");
    m.def("default_candidates",
          [](const BrdfPtr& source, int threads, std::size_t directions, std::uint64_t seed) {
              if (!source) return default_candidates();
              const MetricOptions o = metric_options(80.0, threads, "directions", directions, seed);
              return Interruptible().run([&] { return default_candidates(*source, o); });
          },
          py::arg("source") = py::none(), py::kw_only(), py::arg("threads") = 0,
          py::arg("directions") = MetricOptions{}.directions, py::arg("seed") = MetricOptions{}.seed,
          "select_representation's candidates, cheapest first; for a source, with phi_d kept whole "
          "(keep_phi_d_whole) when it is not reciprocal (is_reciprocal)");
    m.attr("RECIPROCITY_THRESHOLD") = kReciprocityThreshold;
    m.def("is_reciprocal",
          [](const BrdfPtr& source, int threads, std::size_t directions, std::uint64_t seed) {
              const MetricOptions o = metric_options(80.0, threads, "directions", directions, seed);
              return Interruptible().run([&] { return is_reciprocal(*source, o); });
          },
          py::arg("source").none(false), py::kw_only(), py::arg("threads") = 0,
          py::arg("directions") = MetricOptions{}.directions, py::arg("seed") = MetricOptions{}.seed,
          "whether the source's reciprocity error is at most RECIPROCITY_THRESHOLD");
    m.def("keep_phi_d_whole", &keep_phi_d_whole, py::arg("specs"),
          "the specs with symmetry=bilateral where they would fold phi_d by reciprocity (tabular, svd, nmf)");
    m.def("format_of", [](const std::string& path) { return format_of(path); }, py::arg("path"),
          "the format name of a file's extension ('merl', 'rgl', ...)");
}

}  // namespace brdfz::python
