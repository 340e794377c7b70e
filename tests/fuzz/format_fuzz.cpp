// libFuzzer harness for every registered file format (brdfz/formats/registry.h): the format named by
// $BRDFZ_FUZZ_FORMAT reads the input, and what it read is evaluated (and, but for stored tables, whose
// sampler costs far more to build than the file to read, sampled).
#include <cstdio>
#include <cstdlib>

#include "brdfz/errors.h"
#include "brdfz/formats/registry.h"
#include "fuzz_util.h"

namespace {

const brdfz::Format& fuzzed_format() {
    static const brdfz::Format* format = [] {
        const char* name = std::getenv("BRDFZ_FUZZ_FORMAT");
        const brdfz::Format* f = name ? brdfz::find_format(name) : nullptr;
        if (!f) {
            std::fprintf(stderr, "fuzz_format: set BRDFZ_FUZZ_FORMAT to a format of `brdfz formats`\n");
            std::exit(2);
        }
        return f;
    }();
    return *format;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const brdfz::Format& format = fuzzed_format();
    const std::string& path = brdfz::fuzz::input_file(data, size, format.extensions.front().c_str());
    try {
        if (format.read) {
            const brdfz::Loaded loaded = format.read(path, {});
            brdfz::fuzz::exercise(*loaded.brdf, loaded.brdf->stored_table() == nullptr);
        } else if (format.read_measurements) {
            format.read_measurements(path);
        }
    } catch (const brdfz::Error&) {
    }
    return 0;
}
