// The .brdfz container: one HDF5 file holding any brdfz representation with its provenance, its
// conventions and what it achieved. The layout, the metadata and the versioning rules are specified in
// formats/SPEC.md; each representation has its own small storage module (formats/container/).
//
// Integrity: every dataset carries a CRC-32C of its bytes, verified on every read (a mismatch names the
// dataset); HDF5's own checksums cover the file's structure and attributes.
// Versioning: a file lists the features it uses, each with the container version that introduced it;
// a reader refuses a file that needs a feature it does not know, naming the feature.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/table.h"

namespace brdfz::container {

// The container version this library writes, and the newest it reads.
inline constexpr std::uint32_t kVersion = 9;

// A feature a file uses and the container version that introduced it.
struct Feature {
    std::string name;
    std::uint32_t since = 1;
    bool operator==(const Feature&) const = default;
};

// Every feature this library reads (the representations it stores, their element types, ...).
std::vector<Feature> known_features();

struct Source {
    std::string file;    // file name of what the BRDF was read from (no directories); empty if unknown
    std::string format;  // its format ("merl", "rgl", ...)
    std::string sha256;  // SHA-256 of its bytes, 64 hex digits
};

// What the stored representation achieved against what it was given (zfp-style: reported, not asked).
struct Achieved {
    bool lossless = false;      // stored exactly: evaluation is bit-identical to the source object's
    std::uint64_t nbytes = 0;   // bytes of the stored parameters (Brdf::nbytes of what a reader gets)
    ValidityCounts counts;      // a tabulated source: its bins by class
    std::optional<Metrics> metrics;  // not lossless: the stored representation against the source
};

struct DatasetInfo {
    std::string path;  // e.g. "/representation/values"
    std::string dtype;
    std::vector<std::uint64_t> shape;
    std::uint32_t crc32c = 0;
};

struct Metadata {
    std::uint32_t version = 0;             // container version of the writer
    std::uint32_t min_reader_version = 0;  // the newest "since" among the features
    std::vector<Feature> features;
    std::string library_version;  // brdfz version that wrote the file
    std::string created;          // UTC, ISO 8601 (2026-01-31T12:00:00Z)
    Source source;
    std::string units;        // "1/sr": values are f_r
    std::string cosine;       // "excluded": stored values do not include cosθi
    std::string conventions;  // frame and direction conventions (brdf.h)
    std::string representation;  // storage module: "tabular", "rgl", ...
    std::string spec;            // the representation's describe() when written
    std::string build_spec;      // the compress() spec that built it ("svd:rank=4"); empty if none
    Achieved achieved;
    std::vector<DatasetInfo> datasets;  // read_metadata: shapes and stored checksums, not verified
};

struct WriteOptions {
    // File the BRDF was read from: its name, format and SHA-256 are recorded. Empty: none recorded.
    std::string source;
    std::string source_format;
    // As SaveOptions::grid: unset keeps a table's grid (or an RGL file's tensors) and tabulates anything
    // else on 90x90x180; set resamples onto this grid.
    std::optional<GridSpec> grid;
    bool metrics = true;  // when not stored exactly, compare the stored form with the source
    // The compress() spec that built `brdf`, recorded as /representation's build_spec.
    std::string build_spec;
    // Metrics of `brdf` against the original it approximates (compress's source), recorded as the
    // achieved metrics in place of the writer's own comparison.
    std::optional<Metrics> source_metrics;
    int threads = 0;
    std::function<void(double)> progress;
};

// Writes atomically (formats/detail/atomic_file.h). IoError when writing fails.
Achieved write(const std::string& path, const Brdf& brdf, const WriteOptions& options = {});

struct ReadResult {
    std::unique_ptr<Brdf> brdf;
    Metadata meta;
};

// Verifies the format, the features and the checksum of every dataset it reads. FormatError naming the
// file (and the dataset or attribute) for a corrupt or invalid file; UnsupportedError for a valid file
// that needs features this library does not know. `lookup` is used by tables' eval.
ReadResult read(const std::string& path, Lookup lookup = Lookup::Linear);

// The metadata alone (no dataset is read, so checksums are listed, not verified).
Metadata read_metadata(const std::string& path);

}  // namespace brdfz::container
