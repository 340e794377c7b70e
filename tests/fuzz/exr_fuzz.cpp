// libFuzzer harness: OpenEXR table import, then evaluation of what it read.
#include "brdfz/errors.h"
#include "brdfz/formats/exr.h"
#include "brdfz/repr/tabular.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".exr");
    try {
        brdfz::fuzz::exercise(brdfz::TabularBrdf(brdfz::exr::read(path), brdfz::Lookup::Linear), false);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
