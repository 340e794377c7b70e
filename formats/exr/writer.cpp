#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <cmath>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/exr.h"
#include "detail/atomic_file.h"

namespace brdfz::exr {

int tiles_across(int n_phi_d) { return static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n_phi_d)))); }

void write(const std::string& path, const Table& table) {
    const GridSpec& g = table.grid();
    const int across = tiles_across(g.n_phi_d), down = (g.n_phi_d + across - 1) / across;
    const int width = across * g.n_theta_d, height = down * g.n_theta_h;

    // Planar channels for OpenEXR, laid out as the mosaic.
    std::vector<float> planes(3 * static_cast<std::size_t>(width) * height, 0.0f);
    const std::size_t plane = static_cast<std::size_t>(width) * height;
    for (int ip = 0; ip < g.n_phi_d; ++ip) {
        const int x0 = (ip % across) * g.n_theta_d, y0 = (ip / across) * g.n_theta_h;
        for (int ih = 0; ih < g.n_theta_h; ++ih)
            for (int id = 0; id < g.n_theta_d; ++id) {
                const std::size_t pixel = static_cast<std::size_t>(y0 + ih) * width + (x0 + id);
                for (int c = 0; c < 3; ++c) planes[c * plane + pixel] = table.at(g.index(ih, id, ip), c);
            }
    }

    brdfz::detail::AtomicFile out(path);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.insert("brdfz.grid", Imf::StringAttribute(g.str()));
        header.insert("brdfz.bin_position",
                      Imf::StringAttribute(g.position == BinPosition::Centre ? "centre" : "start"));
        header.insert("brdfz.tiles_across", Imf::IntAttribute(across));
        header.insert("brdfz.layout", Imf::StringAttribute("mosaic: one tile per phi_d bin, row-major; in a tile, "
                                                           "rows theta_h, columns theta_d; f_r in 1/sr"));
        Imf::FrameBuffer fb;
        static const char* const kNames[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c) {
            header.channels().insert(kNames[c], Imf::Channel(Imf::FLOAT));
            fb.insert(kNames[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes.data() + c * plane),
                                            sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
        }
        Imf::OutputFile file(out.open_path().c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(height);
    } catch (const std::exception& e) {
        // OpenEXR names the file it was given: the output's, not the name of its temporary.
        std::string what = e.what();
        for (std::size_t at = what.find(out.open_path()); at != std::string::npos;
             at = what.find(out.open_path(), at + path.size()))
            what.replace(at, out.open_path().size(), path);
        throw IoError(path, "cannot write OpenEXR image: " + what);
    }
    out.commit();
}

}  // namespace brdfz::exr
