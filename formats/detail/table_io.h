// What the formats that hold Rusinkiewicz tables (MERL, EXR, the container) share in load and save.
#pragma once

#include <functional>

#include "brdfz/formats/io.h"

namespace brdfz::detail {

// SourceInfo of a table read from a file: its dims, the range of its valid values, and `counts`.
SourceInfo table_info(const std::string& format, const Table& table, const ValidityCounts& counts);

// Writes `brdf` through `write` as a table: a table on the requested grid (or its own, without a
// warped θd axis) as it is, anything else tabulated first (on options.grid, default MERL's).
ValidityCounts save_table(const Brdf& brdf, const SaveOptions& options, const std::function<void(const Table&)>& write);

}  // namespace brdfz::detail
