// brdfz formats [--json]: the registered file formats (formats/include/brdfz/formats/registry.h).
#include <iomanip>
#include <iostream>

#include "brdfz/formats/registry.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

// "brdf", "measurements" or "" (not read).
std::string reads(const Format& f) { return f.read ? "brdf" : f.read_measurements ? "measurements" : ""; }

std::string extensions(const Format& f) {
    std::string out;
    for (const std::string& e : f.extensions) out += (out.empty() ? "" : " ") + e;
    return out;
}

}  // namespace

void add_formats(CLI::App& app) {
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("formats", "the file formats brdfz reads and writes");
    cmd->add_flag("--json", *json, "print JSON");
    cmd->callback([json] {
        if (*json) {
            JsonWriter j(std::cout);
            j.begin_array();
            for (const Format& f : all_formats()) {
                j.begin_object();
                j.key("name").value(f.name);
                j.key("description").value(f.description);
                j.key("extensions").begin_array();
                for (const std::string& e : f.extensions) j.value(e);
                j.end_array();
                j.key("reads").value(reads(f));
                j.key("writes").value(f.write != nullptr);
                j.end_object();
            }
            j.end_array();
            std::cout << "\n";
            return;
        }
        std::cout << std::left << std::setw(9) << "format" << std::setw(10) << "extension" << std::setw(14) << "reads"
                  << std::setw(7) << "writes" << "description\n";
        for (const Format& f : all_formats())
            std::cout << std::setw(9) << f.name << std::setw(10) << extensions(f) << std::setw(14)
                      << (reads(f).empty() ? "-" : reads(f)) << std::setw(7) << (f.write ? "yes" : "no") << f.description
                      << "\n";
    });
}

}  // namespace brdfz::cli
