#include "brdfz/formats/io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/exr.h"
#include "brdfz/formats/alta.h"
#include "brdfz/formats/cornell.h"
#include "brdfz/formats/merl.h"
#include "brdfz/formats/model_json.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/tabulate.h"

namespace brdfz {
namespace {

// Range of a table's valid values.
void value_range(const Table& t, SourceInfo& info) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t k = 0; k < 3 * t.bins(); ++k) {
        const float v = t.data()[k];
        if (std::isnan(v)) continue;
        lo = std::min<double>(lo, v);
        hi = std::max<double>(hi, v);
    }
    info.min_value = lo <= hi ? lo : 0.0;
    info.max_value = lo <= hi ? hi : 0.0;
}

Loaded load_merl(const std::string& path, const LoadOptions& options) {
    merl::ReadResult r = merl::read(path, options.position);
    const GridSpec& g = r.table.grid();
    Loaded out;
    out.info.format = "merl";
    out.info.dims = {static_cast<std::size_t>(g.n_theta_h), static_cast<std::size_t>(g.n_theta_d),
                     static_cast<std::size_t>(g.n_phi_d)};
    out.info.counts = r.counts;
    value_range(r.table, out.info);
    out.brdf = std::make_unique<TabularBrdf>(std::move(r.table), options.lookup);
    return out;
}

Loaded load_rgl(const std::string& path) {
    rgl::ReadResult r = rgl::read(path);
    Loaded out;
    out.info.format = "rgl";
    out.info.dims = std::move(r.dims);
    out.info.counts = r.counts;
    out.info.min_value = r.min_value;
    out.info.max_value = r.max_value;
    out.brdf = std::move(r.brdf);
    return out;
}

Loaded load_brdfz(const std::string& path, const LoadOptions& options) {
    container::ReadResult r = container::read(path, options.lookup);
    Loaded out;
    out.info.format = "brdfz";
    out.info.counts = r.meta.achieved.counts;
    if (const auto* t = dynamic_cast<const TabularBrdf*>(r.brdf.get())) {
        const GridSpec& g = t->table().grid();
        out.info.dims = {static_cast<std::size_t>(g.n_theta_h), static_cast<std::size_t>(g.n_theta_d),
                         static_cast<std::size_t>(g.n_phi_d)};
        value_range(t->table(), out.info);
    }
    out.brdf = std::move(r.brdf);
    return out;
}

// An analytic model file: dims is its parameter count, the range that of its parameter values.
Loaded load_json(const std::string& path) {
    auto model = std::make_unique<AnalyticBrdf>(model_json::read(path));
    Loaded out;
    out.info.format = "json";
    out.info.dims = {model->params().size()};
    out.info.counts.valid = model->params().size();
    const auto [lo, hi] = std::minmax_element(model->params().begin(), model->params().end());
    out.info.min_value = *lo;
    out.info.max_value = *hi;
    out.brdf = std::move(model);
    return out;
}

// Table formats: a table on the requested grid (or its own) is written as it is, anything else is
// tabulated first. MERL and EXR files know only the linear θd axis and the reciprocal φd axis, so a
// warped table is tabulated too, and a table over the full φd circle onto half as many φd bins over
// [0, π) (each the mean of the pair and its exchange, tabulate.h).
template <typename Write>
ValidityCounts save_table(const Brdf& brdf, const SaveOptions& options, const Write& write) {
    if (options.grid && !options.grid->reciprocal())
        throw ValueError("MERL and EXR tables fold phi_d by reciprocity: a grid with symmetry none needs .brdfz");
    const auto* table = dynamic_cast<const TabularBrdf*>(&brdf);
    const auto plain = [](const GridSpec& g) { return g.theta_d_warp == 0.0 && g.reciprocal(); };
    if (table && plain(table->table().grid()) && (!options.grid || *options.grid == table->table().grid())) {
        write(table->table());
        ValidityCounts written;
        written.valid = table->table().valid_bins();
        return written;
    }
    TabulateOptions t;
    t.grid = options.grid.value_or(GridSpec{});
    if (table && !options.grid) {  // its own grid on the linear θd axis and the reciprocal φd axis
        t.grid = table->table().grid();
        t.grid.theta_d_warp = 0.0;
        if (!t.grid.reciprocal()) t.grid.n_phi_d = std::max(1, t.grid.n_phi_d / 2);
        t.grid.symmetry = Symmetry::Reciprocal;
    }
    t.threads = options.threads;
    t.progress = options.progress;
    Tabulated tab = tabulate(brdf, t);
    write(tab.table);
    return tab.counts;
}

}  // namespace

std::string format_of(const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".binary") return "merl";
    if (ext == ".bsdf") return "rgl";
    if (ext == ".brdfz") return "brdfz";
    if (ext == ".exr") return "exr";
    if (ext == ".brdf") return "cornell";
    if (ext == ".dat") return "alta";
    if (ext == ".json") return "json";
    throw FormatError(path, "unknown file extension '" + ext + "' (expected .binary, .bsdf, .brdfz, .brdf, .dat or .json)");
}

Loaded load(const std::string& path, const LoadOptions& options) { return load_as(format_of(path), path, options); }

Loaded load_as(const std::string& format, const std::string& path, const LoadOptions& options) {
    if (format == "merl") return load_merl(path, options);
    if (format == "rgl") return load_rgl(path);
    if (format == "brdfz") return load_brdfz(path, options);
    if (format == "exr") {
        Loaded out;
        out.info.format = "exr";
        Table t = exr::read(path);
        const GridSpec& g = t.grid();
        out.info.dims = {static_cast<std::size_t>(g.n_theta_h), static_cast<std::size_t>(g.n_theta_d),
                         static_cast<std::size_t>(g.n_phi_d)};
        out.info.counts.valid = t.valid_bins();
        value_range(t, out.info);
        out.brdf = std::make_unique<TabularBrdf>(std::move(t), options.lookup);
        return out;
    }
    if (format == "json") return load_json(path);
    if (format == "cornell" || format == "alta")
        throw UnsupportedError(path, "a " + format + " file holds scattered measurements, not a BRDF: it can be the " +
                                         "reference of a comparison or be fitted, not evaluated");
    throw UnsupportedError(path, "reading " + format + " files is not supported");
}

bool holds_measurements(const std::string& path) {
    const std::string format = format_of(path);
    return format == "cornell" || format == "alta";
}

LoadedMeasurements load_measurements(const std::string& path) {
    const std::string format = format_of(path);
    LoadedMeasurements out;
    out.info.format = format;
    if (format == "cornell") {
        cornell::ReadResult r = cornell::read(path);
        out.info.dims = {r.records, r.wavelengths.size()};
        out.info.counts = r.counts;
        out.set = std::move(r.set);
    } else if (format == "alta") {
        alta::ReadResult r = alta::read(path);
        out.info.dims = {r.rows, static_cast<std::size_t>(r.set.channels)};
        out.info.counts = r.counts;
        out.set = std::move(r.set);
    } else {
        throw UnsupportedError(path, "a " + format + " file holds a BRDF, not scattered measurements: load it with load()");
    }
    // Readers keep only finite samples, and at least one.
    out.info.min_value = out.info.max_value = out.set.samples.front().f[0];
    for (const Measurement& m : out.set.samples)
        for (double v : m.f) {
            out.info.min_value = std::min(out.info.min_value, v);
            out.info.max_value = std::max(out.info.max_value, v);
        }
    return out;
}

ValidityCounts save(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    const std::string format = options.format.empty() ? format_of(path) : options.format;
    if (format == "brdfz") {
        container::WriteOptions w;
        w.source = options.source;
        w.source_format = options.source_format;
        w.grid = options.grid;
        w.threads = options.threads;
        w.progress = options.progress;
        w.build_spec = options.build_spec;
        w.source_metrics = options.source_metrics;
        return container::write(path, brdf, w).counts;
    }
    if (format == "json") {
        const auto* model = dynamic_cast<const AnalyticBrdf*>(&brdf);
        if (!model) throw UnsupportedError(path, "only analytic models can be written as .json (brdfz fit makes them)");
        model_json::write(path, *model);
        return {};
    }
    if (format == "merl") return save_table(brdf, options, [&](const Table& t) { merl::write(path, t); });
    if (format == "rgl") {
        ValidityCounts written;
        rgl::WriteOptions w;
        w.n_phi_i = options.rgl_phi_i;
        written.valid = rgl::write(path, brdf, w);
        return written;
    }
    if (format == "exr") return save_table(brdf, options, [&](const Table& t) { exr::write(path, t); });
    throw UnsupportedError(path, "writing " + format + " files is not supported");
}

}  // namespace brdfz
