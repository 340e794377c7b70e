// Small tables and text for the formats' example files (Format::examples).
#pragma once

#include <fstream>
#include <string>

#include "brdfz/table.h"

namespace brdfz::detail {

// A table of the given grid with distinct values per bin and channel, its first bin invalid.
inline Table example_table(GridSpec g) {
    Table t(g);
    for (std::size_t k = 0; k < t.bins(); ++k) t.set(k, {0.1 + 0.01 * k, 0.2, 0.3 + 0.02 * (k % 3)});
    t.invalidate(0);
    return t;
}

inline void write_text(const std::string& path, const char* text) { std::ofstream(path) << text; }

}  // namespace brdfz::detail
