// libFuzzer harness: the .brdfz container's metadata reader (attributes and dataset listing, which
// format_fuzz's reads do not go through).
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".brdfz");
    try {
        brdfz::container::read_metadata(path);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
