// Format-independent loading and saving: the format comes from the file extension.
//   .binary  MERL table            (read, write)
//   .bsdf    RGL-EPFL tensor_file  (read; write isotropic RGB: brdfz/formats/rgl_writer.h)
//   .brdfz   brdfz container       (read, write; formats/SPEC.md)
//   .exr     OpenEXR table mosaic  (read, write; brdfz/formats/exr.h)
//   .brdf    Cornell spectral measurements  (read with load_measurements)
//   .dat     ALTA text measurements         (read with load_measurements)
//   .json    analytic model                 (read, write; docs/model-json.md)
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/measurements.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/table.h"

namespace brdfz {

// What a reader found in the file, beside the Brdf itself.
struct SourceInfo {
    std::string format;              // "merl", "rgl"
    std::vector<std::size_t> dims;   // the stored array's shape
    // MERL: bins by class, range of f_r in 1/sr. RGL: the stored `rgb` tensor's values by class and
    // their range, in the file's units (f·cosθo over the warped domain, before the Jacobian).
    // Cornell ("cornell", dims {records, wavelengths}) and ALTA ("alta", dims {rows, 1}): records by
    // class as cornell.h / alta.h define them, range of the kept samples' f_r in 1/sr.
    ValidityCounts counts;
    double min_value = 0, max_value = 0;
};

struct Loaded {
    std::unique_ptr<Brdf> brdf;
    SourceInfo info;
};

// Scattered measurements (Cornell, ALTA) and what the reader found.
struct LoadedMeasurements {
    MeasurementSet set;
    SourceInfo info;
};

struct LoadOptions {
    BinPosition position = BinPosition::Centre;  // tables: where samples sit in their bins
    Lookup lookup = Lookup::Linear;              // tables: lookup used by eval
};

struct SaveOptions {
    // Table resolution to write. Unset: a TabularBrdf keeps its own grid (a warped θd axis, which MERL
    // and EXR files cannot hold, becomes the linear one), anything else is tabulated on MERL's 90x90x180.
    // A table on another grid is resampled (tabulated through its lookup).
    std::optional<GridSpec> grid;
    int threads = 0;
    std::function<void(double)> progress;  // tabulation progress, fraction done
    // Format name overriding the extension; empty: from the extension.
    std::string format;
    // File the BRDF was read from and its format, recorded by writers that keep provenance (.brdfz).
    std::string source, source_format;
    // .brdfz: the compress() spec that built the BRDF, and its metrics against the original (container.h).
    std::string build_spec;
    std::optional<Metrics> source_metrics;
    // .bsdf: φi slices, 1 for an isotropic file, 3..4096 for an anisotropic one (rgl_writer.h).
    int rgl_phi_i = 1;
};

// "merl" / "rgl" / "cornell" / "alta" from the extension; FormatError naming the file otherwise.
std::string format_of(const std::string& path);

Loaded load(const std::string& path, const LoadOptions& options = {});
// As load, for a named format ("merl", "rgl", "brdfz", ...) whatever the extension. A .brdfz table
// carries its own bin position, which takes precedence over options.position.
Loaded load_as(const std::string& format, const std::string& path, const LoadOptions& options = {});

// True when the file's format holds scattered measurements (Cornell .brdf, ALTA .dat), which
// load_measurements reads and load rejects; FormatError for an unknown extension.
bool holds_measurements(const std::string& path);

// Cornell .brdf or ALTA .dat; UnsupportedError for formats that hold a BRDF (use load).
LoadedMeasurements load_measurements(const std::string& path);

// Writes atomically; returns the counts of what was written.
ValidityCounts save(const Brdf& brdf, const std::string& path, const SaveOptions& options = {});

}  // namespace brdfz
