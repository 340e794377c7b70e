// Reports printed by several subcommands (info and demo, diff and demo), as text or JSON.
#pragma once

#include <ostream>
#include <string>

#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "output.h"

namespace brdfz::cli {

// Directional albedo is reported at these view elevations (degrees).
inline constexpr double kAlbedoAnglesDeg[] = {0.0, 30.0, 60.0, 80.0};
// Samples for the sampler's albedo estimate shown beside the quadrature value.
inline constexpr std::size_t kAlbedoSamples = 65536;

// `container`: a .brdfz file's metadata, printed after the rest (JSON: key "container").
// The keys every `info --json` starts with: file, format, dims and the validity counts.
void write_source_keys(JsonWriter& j, const std::string& path, const SourceInfo& info);

// The lines every `info` text starts with: the path, format, dims, what the data is stored as, its
// size and the validity counts. `notes` follow the dims and the counts (what they count, what became
// of such values).
struct SourceNotes {
    std::string dims, negative, nan, inf;
};
void print_source_lines(std::ostream& os, const std::string& path, const SourceInfo& info, const std::string& describe,
                        std::size_t nbytes, const SourceNotes& notes = {});

void print_info(const std::string& path, const Loaded& loaded, bool json, std::ostream& os,
                const container::Metadata* container = nullptr);
void print_metrics(const Metrics& m, bool json, std::ostream& os, Over over = Over::Grid);
// The metrics as one JSON object value: {cos_rmse: {r, g, b, mean}, ..., samples, negatives}.
void write_metrics(JsonWriter& j, const Metrics& m);

}  // namespace brdfz::cli
