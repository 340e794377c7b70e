// OpenEXR table mosaics (brdfz/formats/exr.h) in the format registry.

#include "brdfz/formats/exr.h"
#include "brdfz/formats/registry.h"
#include "brdfz/repr/tabular.h"
#include "detail/examples.h"
#include "detail/table_io.h"

namespace brdfz::formats {
namespace {

Loaded read(const std::string& path, const LoadOptions& options) {
    Table t = exr::read(path);
    const ValidityCounts counts = detail::invalidate_out_of_range(path, t);
    Loaded out;
    out.info = detail::table_info("exr", t, counts);
    out.brdf = std::make_unique<TabularBrdf>(std::move(t), options.lookup, options.sampler);
    return out;
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    return detail::save_table(brdf, options, [&](const Table& t) { exr::write(path, t); });
}

bool sniff(std::string_view head, std::uintmax_t) { return head.substr(0, 4) == std::string_view("\x76\x2f\x31\x01", 4); }

void examples(const std::string& dir) {
    exr::write(dir + "/a.exr", detail::example_table({2, 2, 2}));
    exr::write(dir + "/b.exr", detail::example_table({3, 2, 5, BinPosition::Start}));
}

}  // namespace

void register_exr(std::vector<Format>& out) {
    out.push_back({"exr", "OpenEXR image of a table (a mosaic of φd tiles)", {".exr"}, sniff, read, nullptr, write,
                   examples});
}

}  // namespace brdfz::formats
