// brdfz info FILE [--json]
#include <iostream>

#include "commands.h"
#include "output.h"
#include "report.h"

namespace brdfz::cli {
namespace {

// Scattered measurements have no BRDF to integrate: albedo is an empty array in JSON (the same type
// as for a BRDF, so readers iterate over nothing) and said to be undefined in text.
void print_measurement_info(const std::string& path, const LoadedMeasurements& m, bool json, std::ostream& os) {
    const SourceInfo& info = m.info;
    const std::size_t nbytes = m.set.samples.size() * sizeof(Measurement);
    const std::string describe = std::to_string(m.set.samples.size()) + " measurements (wi, wo, f as float64), " +
                                 (m.set.channels == 1 ? "monochrome" : "linear sRGB");
    if (json) {
        JsonWriter j(os);
        j.begin_object();
        write_source_keys(j, path, info);
        j.key("below_horizon").value(info.counts.below_horizon);
        j.key("samples").value(m.set.samples.size());
        j.key("min").value(info.min_value);
        j.key("max").value(info.max_value);
        j.key("nbytes").value(nbytes);
        j.key("channels").value(static_cast<std::size_t>(m.set.channels));
        j.key("describe").value(describe);
        j.key("albedo").begin_array().end_array();
        j.end_object();
        os << "\n";
        return;
    }
    print_source_lines(os, path, info, describe, nbytes,
                       {info.format == "cornell" ? " (records x wavelengths)" : " (rows x values)", " (kept)",
                        " (dropped)", " (dropped)"});
    os << "  horizon    " << info.counts.below_horizon << " on or below the horizon (dropped)\n"
       << "  range      [" << number(info.min_value) << ", " << number(info.max_value) << "] 1/sr\n"
       << "  albedo     not defined for scattered samples (no BRDF to integrate)\n";
}

}  // namespace

void add_info(CLI::App& app) {
    struct Args {
        std::string file;
        bool json = false;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("info", "format, dimensions, validity counts, value range, albedo, size");
    cmd->add_option("FILE", args->file, "input file")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        if (holds_measurements(args->file))
            print_measurement_info(args->file, load_measurements(args->file), args->json, std::cout);
        else if (detect_format(args->file) == "brdfz") {
            const container::Metadata meta = container::read_metadata(args->file);
            print_info(args->file, load(args->file, args->load), args->json, std::cout, &meta);
        } else
            print_info(args->file, load(args->file, args->load), args->json, std::cout);
    });
}

}  // namespace brdfz::cli
