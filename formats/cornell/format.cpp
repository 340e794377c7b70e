// Cornell spectral measurements (brdfz/formats/cornell.h) in the format registry.
#include <charconv>
#include <sstream>

#include "brdfz/formats/cornell.h"
#include "brdfz/formats/registry.h"
#include "detail/examples.h"

namespace brdfz::formats {
namespace {

LoadedMeasurements read(const std::string& path) {
    cornell::ReadResult r = cornell::read(path);
    LoadedMeasurements out;
    out.info.dims = {r.records, r.wavelengths.size()};
    out.info.counts = r.counts;
    out.set = std::move(r.set);
    return out;
}

// Text whose first line that is neither a comment nor blank is a wavelength count alone.
bool sniff(std::string_view head, std::uintmax_t) {
    std::size_t pos = 0;
    while (pos < head.size()) {
        const std::size_t end = std::min(head.find('\n', pos), head.size());
        std::string_view line = head.substr(pos, end - pos);
        pos = end + 1;
        const std::size_t a = line.find_first_not_of(" \t\r");
        if (a == std::string_view::npos || line[a] == '#') continue;
        line = line.substr(a, line.find_last_not_of(" \t\r") - a + 1);
        int n = 0;
        const auto [p, ec] = std::from_chars(line.data(), line.data() + line.size(), n);
        return ec == std::errc() && p == line.data() + line.size() && n > 0;
    }
    return false;
}

// The shipped files' layout: 31 wavelengths from 400 to 700 nm, records θi φi θo φo and 31 values.
void examples(const std::string& dir) {
    std::ostringstream text;
    text << "# Cornell-style test file\n31\n";
    for (int nm = 400; nm <= 700; nm += 10) text << nm << (nm < 700 ? " " : "\n");
    const char* angles[] = {"0.1 0 0.2 3.1", "0.3 0.5 0.3 3.6", "1.0 0 0.9 3.14"};
    for (int r = 0; r < 3; ++r) {
        text << angles[r];
        for (int k = 0; k < 31; ++k) text << " " << 0.2 + 0.01 * k + 0.1 * r;
        text << "\n";
    }
    detail::write_text(dir + "/a.brdf", text.str().c_str());
}

}  // namespace

void register_cornell(std::vector<Format>& out) {
    out.push_back({"cornell", "Cornell gonioreflectometer spectral measurements (scattered samples)", {".brdf"}, sniff,
                   nullptr, read, nullptr, examples});
}

}  // namespace brdfz::formats
