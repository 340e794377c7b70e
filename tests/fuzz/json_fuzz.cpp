// libFuzzer harness: the JSON readers — an analytic model (then evaluated) and a scene (then built).
#include "brdfz/errors.h"
#include "brdfz/formats/model_json.h"
#include "brdfz/formats/scene_json.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".json");
    try {
        brdfz::fuzz::exercise(brdfz::model_json::read(path), true);
    } catch (const brdfz::Error&) {
    }
    try {
        brdfz::build_scene(brdfz::scene_json::read(path));
    } catch (const brdfz::Error&) {
    }
    return 0;
}
