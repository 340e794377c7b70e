// The MERL .binary format (brdfz/formats/merl.h) in the format registry.

#include "brdfz/formats/merl.h"
#include "brdfz/formats/registry.h"
#include "brdfz/repr/tabular.h"
#include "detail/examples.h"
#include "detail/table_io.h"

namespace brdfz::formats {
namespace {

Loaded read(const std::string& path, const LoadOptions& options) {
    merl::ReadResult r = merl::read(path, options.position);
    Loaded out;
    out.info = detail::table_info("merl", r.table, r.counts);
    out.brdf = std::make_unique<TabularBrdf>(std::move(r.table), options.lookup, options.sampler);
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    return detail::save_table(brdf, options, [&](const Table& t) { merl::write(path, t); });
}

// Three positive little-endian int32 dims whose three float64 planes fill the rest of the file.
bool sniff(std::string_view head, std::uintmax_t size) {
    if (head.size() < 12) return false;
    std::uintmax_t bins = 1;
    for (int k = 0; k < 3; ++k) {
        const auto* b = reinterpret_cast<const unsigned char*>(head.data() + 4 * k);
        const std::uint32_t n = b[0] | (b[1] << 8) | (b[2] << 16) | (std::uint32_t{b[3]} << 24);
        if (n == 0 || n > 1u << 16) return false;
        bins *= n;
    }
    return 12 + 24 * bins == size;
}

void examples(const std::string& dir) {
    merl::write(dir + "/a.binary", detail::example_table({2, 2, 2}));
    merl::write(dir + "/b.binary", detail::example_table({3, 1, 5}));
}

}  // namespace

void register_merl(std::vector<Format>& out) {
    out.push_back({"merl", "MERL table (Matusik et al. 2003)", {".binary"}, sniff, read, nullptr, write, examples});
}

}  // namespace brdfz::formats
