// libFuzzer harness: .brdfz container reader (envelope, HDF5 structure, storage modules), metadata
// reader, then evaluation of what it read.
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".brdfz");
    try {
        const brdfz::container::ReadResult r = brdfz::container::read(path);
        brdfz::fuzz::exercise(*r.brdf, r.meta.representation != "tabular");
        brdfz::container::read_metadata(path);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
