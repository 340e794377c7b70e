// Output helpers shared by the subcommands: number formatting, progress display and the options
// every loading command takes.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "brdfz/formats/io.h"
#include "brdfz/formats/json_writer.h"
#include "brdfz/metrics.h"

namespace brdfz::cli {

// Shortest text that reads back to the same double ("%.17g").
std::string number(double v);
// The same, appended to `out` (no string of its own: rows of many numbers).
void append_number(std::string& out, double v);

// The --json reports, one line each.
using JsonWriter = json::Writer;

// "label NN%" on stderr while a long operation runs, only when stderr is a terminal.
std::function<void(double)> progress_bar(const std::string& label);

// --bin-position and --lookup, shared by every command that loads files.
void add_load_options(CLI::App* cmd, LoadOptions& options);

// --over grid|directions, --directions N and --seed S: where the metrics are taken (metrics.h). Returns
// --over, whose default is options.over's (grid unless the command sets another).
CLI::Option* add_over_options(CLI::App* cmd, MetricOptions& options);
// The help text of --over, which diff and compress print.
extern const char* const kOverHelp;

// Parses exactly `count` comma-separated numbers; false on anything else.
bool parse_numbers(const std::string& text, double* out, int count);
// Unit direction from a user vector into `out`; false for zero or non-finite vectors.
bool to_unit(const double* v, Vec3& out);
// Unit direction from a user vector; ValueError naming `where` for zero or non-finite vectors.
Vec3 unit_direction(const double* v, const std::string& where);
// "x,y,z" -> unit direction; ValueError naming the option otherwise.
Vec3 parse_direction(const std::string& text, const std::string& option);

// A check for unsigned integer options (seeds): plain decimal digits within uint64_t. CLI11 alone wraps
// "-1" round to 2^64 - 1 and saturates values past the range.
CLI::Validator unsigned_integer();

// --threads, bounded by kMaxThreads (brdfz/control.h) when the command line is parsed.
void add_threads_option(CLI::App* cmd, int& threads);

// "90x90x180" -> GridSpec; ValueError otherwise.
GridSpec parse_resolution(const std::string& text);

}  // namespace brdfz::cli
