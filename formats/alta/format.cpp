// ALTA text measurements (brdfz/formats/alta.h) in the format registry.
#include "brdfz/formats/alta.h"
#include "brdfz/formats/registry.h"
#include "detail/examples.h"

namespace brdfz::formats {
namespace {

LoadedMeasurements read(const std::string& path) {
    alta::ReadResult r = alta::read(path);
    LoadedMeasurements out;
    out.info.dims = {r.rows, static_cast<std::size_t>(r.set.channels)};
    out.info.counts = r.counts;
    out.set = std::move(r.set);
    return out;
}

// ALTA's header states the data's dimensions in a `#DIM` line.
bool sniff(std::string_view head, std::uintmax_t) {
    return head.substr(0, 5) == "#DIM " || head.find("\n#DIM ") != std::string_view::npos;
}

void examples(const std::string& dir) {
    detail::write_text(dir + "/a.dat",
                       "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n#VS 0\n"
                       "#ALTA HEADER END\n0.1 0.2 0.3 0.5\n0.2 0.1 -0.1 0.7\n0.5 0.0 0.0 2.5\n");
    detail::write_text(dir + "/b.dat", "#DIM 3 1\n#PARAM_IN RUSIN_TH_TD_PD\n0.1 0.2 0.3 0.5\n0.4 0.1 1.2 0.2\n");
    detail::write_text(dir + "/c.dat",
                       "#DIM 6 3\n#PARAM_IN CARTESIAN\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n#VS 1\n"
                       "0 0 1 0.6 0 0.8 0.1 0.2 0.3 0.01\n0.3 0.4 0.866 0 0 1 0.4 0.5 0.6 0.02\n");
    detail::write_text(dir + "/d.dat",
                       "#DIM 4 3\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT RGB_COLOR\n0.4 1 0.9 -2 0.1 0.2 0.3\n");
}

}  // namespace

void register_alta(std::vector<Format>& out) {
    out.push_back({"alta", "ALTA text measurements (scattered samples)", {".dat"}, sniff, nullptr, read, nullptr,
                   examples});
}

}  // namespace brdfz::formats
