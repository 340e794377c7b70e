// libFuzzer harness: Cornell .brdf reader.
#include "brdfz/errors.h"
#include "brdfz/formats/cornell.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".brdf");
    try {
        brdfz::cornell::read(path);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
