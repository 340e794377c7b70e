// The fuzz harnesses' seed corpus and their list: small valid files of every registered format, made
// by each format's Format::examples (no shared data is used or committed).
//   fuzz_seeds --list   the harness runs: one line "format NAME" per format, then the other harnesses
//   fuzz_seeds DIR      DIR/<run>/<seed files> for each
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "brdfz/formats/registry.h"

namespace fs = std::filesystem;
using namespace brdfz;

int main(int argc, char** argv) try {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fuzz_seeds DIR | --list\n");
        return 2;
    }
    if (std::string(argv[1]) == "--list") {
        for (const Format& f : all_formats()) std::printf("format %s\n", f.name.c_str());
        std::printf("scene\nmetadata\n");
        return 0;
    }
    const fs::path dir = argv[1];
    for (const Format& f : all_formats()) {
        fs::create_directories(dir / f.name);
        if (f.examples) f.examples((dir / f.name).string());
    }
    fs::create_directories(dir / "metadata");
    find_format("brdfz")->examples((dir / "metadata").string());
    fs::create_directories(dir / "scene");
    std::ofstream(dir / "scene" / "scene.json")
        << "{\"format\": \"brdfz-scene\", \"version\": 1, \"name\": \"s\", \"seed\": 3, \"views\": [{\"axis\": [0, 0, 1], "
           "\"max_angle_deg\": 20, \"count\": 4}], \"lights\": [{\"direction\": [0, 0.1, 1], \"spread_deg\": 2, "
           "\"intensity\": 1, \"samples\": 2}], \"environment\": {\"radiance\": 0.1, \"samples\": 4}, "
           "\"pairs\": [{\"wi\": [0, 0.5, 1], \"wo\": [0, -0.5, 1], \"weight\": 2}]}\n";
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
}
