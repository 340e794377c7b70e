// libFuzzer harness: the scene reader (docs/scene-json.md), then the scene built from what it read.
#include "brdfz/errors.h"
#include "brdfz/formats/scene_json.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".json");
    try {
        brdfz::build_scene(brdfz::scene_json::read(path));
    } catch (const brdfz::Error&) {
    }
    return 0;
}
