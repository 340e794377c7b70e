// File formats, each registered from its own folder formats/NAME/: its format.cpp defines
// `void brdfz::formats::register_NAME(std::vector<Format>&)`, which the build finds and calls
// (cmake/registry.cmake). load(), save(), `brdfz formats`, Python's brdfz.formats() and the fuzz and
// conformance tests all go through this list, so a new format needs no edit of a central file.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "brdfz/formats/io.h"

namespace brdfz {

struct Format {
    std::string name;                     // "merl": --from/--to, SourceInfo::format
    std::string description;              // one line, e.g. "MERL table"
    std::vector<std::string> extensions;  // ".binary"; the first is the one it is known by
    // True when a file's first bytes (`head`, up to kSniffBytes) and size are this format's; for files
    // whose extension names no format.
    bool (*sniff)(std::string_view head, std::uintmax_t size) = nullptr;
    // At most one of the two readers: a BRDF, or scattered measurements (Cornell, ALTA).
    Loaded (*read)(const std::string& path, const LoadOptions& options) = nullptr;
    LoadedMeasurements (*read_measurements)(const std::string& path) = nullptr;
    ValidityCounts (*write)(const Brdf& brdf, const std::string& path, const SaveOptions& options) = nullptr;
    // Writes a few small valid files of this format into `dir` (made by the format's own writer where
    // it has one): the fuzzers' seeds and the conformance tests' inputs.
    void (*examples)(const std::string& dir) = nullptr;

    static constexpr std::size_t kSniffBytes = 256;
};

// Every registered format, in name order.
const std::vector<Format>& all_formats();
// nullptr for an unknown name.
const Format* find_format(std::string_view name);

}  // namespace brdfz
