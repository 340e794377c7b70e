// OpenEXR images of a Rusinkiewicz table, for looking at a table and editing it with image tools.
//
// Layout ("mosaic"): one tile per φd bin, nθh rows (θh bin 0 at the top) by nθd columns (θd bin 0 at
// the left), tiles placed row-major, `tiles_across` = ceil(√nφd) per row; pixels of unused tiles
// are 0. Channels R, G, B are 32-bit float f_r in 1/sr (invalid entries NaN, as the table holds
// them), ZIP-compressed (lossless), so a table round-trips bit for bit. The grid and layout are
// recorded in header attributes brdfz.grid ("90x90x180"), brdfz.bin_position ("centre" | "start"),
// brdfz.tiles_across and brdfz.layout, which import requires.
#pragma once

#include <string>

#include "brdfz/table.h"

namespace brdfz::exr {

// Tiles per row of the mosaic for nφd tiles.
int tiles_across(int n_phi_d);

// Writes atomically; IoError on failure.
void write(const std::string& path, const Table& table);

// Reads an image written by write(). Checks the attributes, channels and size against each other
// before allocating: FormatError naming the file for anything else, IoError when it cannot be read.
// Tables above 2^24 bins are refused, and OpenEXR is told (process-wide, once) to refuse images wider
// or taller than 2^18 pixels and tiles above 4096², which it would otherwise allocate for on opening.
Table read(const std::string& path);

}  // namespace brdfz::exr
