// Format-independent loading and saving: the format comes from the file extension (or, for an
// extension no format claims, from the file's first bytes). The formats are those registered in
// brdfz/formats/registry.h; `brdfz formats` lists them.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/compress.h"
#include "brdfz/measurements.h"
#include "brdfz/sample/grid_sampler.h"
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
    // What dims counts when it is not a stored array's shape (.json and .brdfz objects: "parameters",
    // "grid of the rank-4 svd factors"); empty otherwise.
    std::string dims_of;
    // False when nothing stored is a value to take a range of (factors): min_value and max_value are 0.
    bool has_range = true;
    // RGL: the same counts for each float field (rgl::ReadResult::fields); empty for other formats.
    std::vector<std::pair<std::string, ValidityCounts>> fields;
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
    // Tables read from table formats (MERL, EXR, NumPy): their sampler (sample/grid_sampler.h), built at
    // load. A .brdfz keeps the sampler it was written with.
    SamplerKind sampler = SamplerKind::Compact;
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

// The format a path's extension names: for Access::Read a format that reads it, for Access::Write
// one that writes it. FormatError naming the file and the extensions that would do otherwise.
enum class Access { Read, Write };
std::string format_of(const std::string& path, Access access = Access::Read);
// As format_of for reading, but an extension no format claims is resolved from the file's first
// bytes (Format::sniff); FormatError when none or several match.
std::string detect_format(const std::string& path);

Loaded load(const std::string& path, const LoadOptions& options = {});
// As load, for a named format ("merl", "rgl", "brdfz", ...) whatever the extension. A .brdfz table
// carries its own bin position, which takes precedence over options.position.
Loaded load_as(const std::string& format, const std::string& path, const LoadOptions& options = {});

// True when the file's format holds scattered measurements (Cornell .brdf, ALTA .dat), which
// load_measurements reads and load rejects; FormatError for an unknown format.
bool holds_measurements(const std::string& path);

// Cornell .brdf or ALTA .dat; UnsupportedError for formats that hold a BRDF (use load).
LoadedMeasurements load_measurements(const std::string& path);

// Outputs are regular files: IoError naming `path` when it is something else (a device, a FIFO, a
// socket, a folder) or a symbolic link to one or to nothing; a link to a regular file is written
// through. save() and convert() check it before their work, as a caller of a long one can.
void check_output(const std::string& path);

// Writes atomically; returns the counts of what was written: table bins, or a stored representation's
// entries (parameters, the factors' grid bins, an RGL file's rgb values).
ValidityCounts save(const Brdf& brdf, const std::string& path, const SaveOptions& options = {});

struct ConvertOptions {
    std::string from;   // the input's format; empty: detected (detect_format)
    LoadOptions load;
    SaveOptions save;   // the output's format, grid, threads, progress; convert() sets source and source_format
};

// load → save: any readable file into any writable format (a representation the output format
// cannot hold is tabulated, on save.grid); returns the counts of what was written.
ValidityCounts convert(const std::string& in, const std::string& out, const ConvertOptions& options = {});

// Writes a text file (a report, a CSV) the way every format is written: atomically, with the umask's
// mode or a replaced file's; IoError on failure.
void save_text(const std::string& path, std::string_view text);

// `options` with the file access compress() needs to resolve the files a spec names (pca:basis=FILE).
CompressOptions with_file_access(CompressOptions options);

}  // namespace brdfz
