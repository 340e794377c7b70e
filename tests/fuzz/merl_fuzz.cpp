// libFuzzer harness: MERL .binary reader, then evaluation of what it read.
#include "brdfz/errors.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/tabular.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string& path = brdfz::fuzz::input_file(data, size, ".binary");
    try {
        brdfz::merl::ReadResult r = brdfz::merl::read(path);
        brdfz::fuzz::exercise(brdfz::TabularBrdf(std::move(r.table), brdfz::Lookup::Linear), false);
    } catch (const brdfz::Error&) {
    }
    return 0;
}
