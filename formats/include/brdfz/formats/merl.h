// MERL .binary (Matusik et al. 2003): int32 dims (θh, θd, φd), then three channel-planar float64
// planes, index φd + nφd·(θd + nθd·θh). Raw value × kScale[channel] is f_r. Negative values mark
// unmeasured bins; they, NaN and Inf become invalid entries of the table and are counted.
#pragma once

#include <string>

#include "brdfz/table.h"

namespace brdfz::merl {

inline constexpr Rgb kScale{1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0};
// Raw value written for an invalid (unmeasured) entry.
inline constexpr double kUnmeasured = -1.0;

struct ReadResult {
    Table table;
    ValidityCounts counts;
};

// Validates the whole file's shape before allocating; FormatError / IoError name the file.
// `position` says where the file's samples sit inside their bins (the data does not record it).
ReadResult read(const std::string& path, BinPosition position = BinPosition::Centre);

// Writes any table (any resolution) atomically; invalid entries are written as kUnmeasured.
void write(const std::string& path, const Table& table);

}  // namespace brdfz::merl
