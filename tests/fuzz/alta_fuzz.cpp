// libFuzzer harness: ALTA .dat reader.
#include "brdfz/errors.h"
#include "brdfz/formats/alta.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".dat");
    try {
        brdfz::alta::read(path);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
