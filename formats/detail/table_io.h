// What the formats that hold Rusinkiewicz tables (MERL, EXR, the container) share in load and save.
#pragma once

#include <functional>

#include "brdfz/formats/io.h"

namespace brdfz::detail {

// SourceInfo of a table read from a file: its dims, the range of its valid values, and `counts`.
SourceInfo table_info(const std::string& format, const Table& table, const ValidityCounts& counts);

// The validity rules of a table read from a file whose values are raw floats (EXR): a negative or
// infinite channel becomes invalid (NaN, as the table marks it), and each bin is counted in every class
// one of its channels falls in. FormatError naming `path` when no channel of any bin is valid.
ValidityCounts invalidate_out_of_range(const std::string& path, Table& table);

// Writes `brdf` through `write` as a table: a table on the requested grid (or its own, without a
// warped θd axis) as it is, anything else tabulated first (on options.grid, default MERL's).
ValidityCounts save_table(const Brdf& brdf, const SaveOptions& options, const std::function<void(const Table&)>& write);

}  // namespace brdfz::detail
