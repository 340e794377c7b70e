// libFuzzer harness: RGL .bsdf (tensor_file) reader, then evaluation and sampling of what it read.
#include "brdfz/errors.h"
#include "brdfz/formats/rgl.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".bsdf");
    try {
        const brdfz::rgl::ReadResult r = brdfz::rgl::read(path);
        brdfz::fuzz::exercise(*r.brdf, true);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
