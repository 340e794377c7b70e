#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/exr.h"
#include "detail/bytes.h"

namespace brdfz::exr {
namespace {

// Tables larger than this (16.8 million bins, 11 times MERL's; 12 bytes a bin, twice while reading)
// are refused before allocating: a compressed image can declare a size far beyond its file's.
constexpr std::size_t kMaxBins = std::size_t{1} << 24;

// OpenEXR allocates line and tile buffers from the header while opening a file, before any check of
// ours: limit the data window and tiles it accepts (a process-wide OpenEXR setting, applied once;
// generous for any brdfz mosaic, whose sides stay below 2^18 within kMaxBins).
void limit_openexr() {
    static std::once_flag once;
    std::call_once(once, [] {
        Imf::Header::setMaxImageSize(1 << 18, 1 << 18);
        Imf::Header::setMaxTileSize(1 << 12, 1 << 12);
    });
}

// A little-endian uint32 of the file at p.
std::uint32_t u32_at(const char* p) {
    std::uint32_t v;
    std::memcpy(&v, p, 4);
    return detail::from_little_endian(v);
}

// OpenEXR reads a typed attribute's value by the type's own layout, not by the size the header
// declares for it: a value of another length than declared leaves OpenEXR reading the rest of the
// header from another offset than the one checked here (a fuzzed file's channel list ended early, and
// OpenEXR took the bytes after it for a string attribute of 1 GB). So each value must be exactly what
// its type reads: fixed sizes, a channel list's names and fields, a string vector's lengths. Types
// outside this list are refused (no brdfz image has them; OpenEXR knows more than it lists here).
bool value_has_its_layout(const std::string& type, const std::string& v) {
    static const std::pair<const char*, std::size_t> fixed[] = {
        {"int", 4},        {"float", 4},     {"double", 8},         {"v2i", 8},         {"v2f", 8},
        {"v2d", 16},       {"v3i", 12},      {"v3f", 12},           {"v3d", 24},        {"box2i", 16},
        {"box2f", 16},     {"m33f", 36},     {"m33d", 72},          {"m44f", 64},       {"m44d", 128},
        {"rational", 8},   {"keycode", 28},  {"timecode", 8},       {"tiledesc", 9},    {"compression", 1},
        {"lineOrder", 1},  {"envmap", 1},    {"deepImageState", 1}, {"chromaticities", 32}};
    for (const auto& [name, bytes] : fixed)
        if (type == name) return v.size() == bytes;
    if (type == "string") return true;
    if (type == "floatvector") return v.size() % 4 == 0;
    if (type == "chlist") {  // names (up to 255 characters) each followed by 16 bytes, then an empty name
        for (std::size_t at = 0;;) {
            const std::size_t end = v.find('\0', at);
            if (end == std::string::npos || end - at > 255) return false;
            if (end == at) return end + 1 == v.size();
            at = end + 1 + 16;
        }
    }
    if (type == "stringvector") {  // a 32-bit length before each string
        std::size_t at = 0;
        while (at < v.size()) {
            if (v.size() - at < 4) return false;
            const std::uint32_t n = u32_at(v.data() + at);
            if (n > v.size() - at - 4) return false;
            at += 4 + n;
        }
        return true;
    }
    return false;
}

// The header OpenEXR will parse, checked first: a single-part scanline image (what write() makes)
// whose every attribute fits in the file and has its type's layout (value_has_its_layout), so that no
// declared size makes OpenEXR allocate more than the file holds.
void check_header(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    in.seekg(0, std::ios::end);
    const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
    in.seekg(0);
    const auto u32 = [&]() {
        char b[4] = {};
        in.read(b, 4);
        return u32_at(b);
    };
    const auto name = [&](std::size_t max) {
        std::string s;
        for (char c; in.get(c) && c != '\0';)
            if (s.size() < max) s += c; else return std::string(max + 1, '?');
        return s;
    };
    if (u32() != 20000630u || !in) throw FormatError(path, "not an OpenEXR image (bad magic number)");
    const std::uint32_t version = u32();
    // Bits 9, 11, 12: tiled, deep, multi-part; bit 10: names up to 255 characters instead of 31.
    if ((version & 0xff) != 2 || (version & 0x1a00) != 0)
        throw FormatError(path, "not a single-part scanline OpenEXR image (version field " + std::to_string(version) + ")");
    const std::size_t max_name = version & 0x400 ? 255 : 31;
    for (int k = 0;; ++k) {
        const std::string attr = name(max_name);
        if (!in) throw FormatError(path, "truncated OpenEXR header");
        if (attr.empty()) return;  // the end of the header
        const std::string type = name(max_name);
        const std::uint32_t bytes = u32();
        if (!in || attr.size() > max_name || type.size() > max_name || k > 1000 ||
            bytes > size - static_cast<std::uint64_t>(in.tellg()))
            throw FormatError(path, "corrupt OpenEXR header (attribute '" + attr.substr(0, max_name) +
                                        "' does not fit in the file)");
        std::string value(bytes, '\0');
        in.read(value.data(), bytes);
        if (!in || !value_has_its_layout(type, value))
            throw FormatError(path, "corrupt OpenEXR header (attribute '" + attr + "' of type '" + type +
                                        "' is not " + std::to_string(bytes) + " bytes of that type)");
    }
}

const std::string& string_attr(const std::string& path, const Imf::Header& h, const char* name) {
    const auto* a = h.findTypedAttribute<Imf::StringAttribute>(name);
    if (!a) throw FormatError(path, std::string("not a brdfz table image (no string attribute '") + name + "')");
    return a->value();
}

}  // namespace

Table read(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "cannot read: no such file");
    limit_openexr();
    check_header(path);
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& h = file.header();

        GridSpec g;
        const std::string& grid = string_attr(path, h, "brdfz.grid");
        char tail = 0;
        if (std::sscanf(grid.c_str(), "%dx%dx%d%c", &g.n_theta_h, &g.n_theta_d, &g.n_phi_d, &tail) != 3)
            throw FormatError(path, "attribute brdfz.grid '" + grid + "' is not NHxNDxNP");
        for (int n : {g.n_theta_h, g.n_theta_d, g.n_phi_d})
            if (n < 1 || n > GridSpec::kMaxAxis) throw FormatError(path, "grid " + grid + " out of range");
        if (g.bins() > kMaxBins) throw FormatError(path, "grid " + grid + " is larger than brdfz reads from images");
        const std::string& position = string_attr(path, h, "brdfz.bin_position");
        if (position != "centre" && position != "start")
            throw FormatError(path, "unknown brdfz.bin_position '" + position + "'");
        g.position = position == "centre" ? BinPosition::Centre : BinPosition::Start;
        const auto* across_attr = h.findTypedAttribute<Imf::IntAttribute>("brdfz.tiles_across");
        const int across = tiles_across(g.n_phi_d), down = (g.n_phi_d + across - 1) / across;
        if (!across_attr || across_attr->value() != across)
            throw FormatError(path, "attribute brdfz.tiles_across is missing or not " + std::to_string(across));

        const Imath::Box2i dw = h.dataWindow();
        if (dw.min.x != 0 || dw.min.y != 0) throw FormatError(path, "data window does not start at pixel 0, 0");
        const long width = static_cast<long>(dw.max.x) - dw.min.x + 1, height = static_cast<long>(dw.max.y) - dw.min.y + 1;
        if (width != static_cast<long>(across) * g.n_theta_d || height != static_cast<long>(down) * g.n_theta_h)
            throw FormatError(path, "image is " + std::to_string(width) + "x" + std::to_string(height) +
                                        ", the mosaic of grid " + grid + " needs " +
                                        std::to_string(across * g.n_theta_d) + "x" + std::to_string(down * g.n_theta_h));
        static const char* const kNames[3] = {"R", "G", "B"};
        for (const char* name : kNames) {
            const Imf::Channel* c = h.channels().findChannel(name);
            if (!c || c->type != Imf::FLOAT || c->xSampling != 1 || c->ySampling != 1)
                throw FormatError(path, std::string("channel ") + name + " is missing or not full-resolution float32");
        }

        const std::size_t plane = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
        std::vector<float> planes(3 * plane);
        Imf::FrameBuffer fb;
        for (int c = 0; c < 3; ++c)
            fb.insert(kNames[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes.data() + c * plane),
                                            sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
        file.setFrameBuffer(fb);
        file.readPixels(0, dw.max.y);

        Table table(g);
        for (int ip = 0; ip < g.n_phi_d; ++ip) {
            const int x0 = (ip % across) * g.n_theta_d, y0 = (ip / across) * g.n_theta_h;
            for (int ih = 0; ih < g.n_theta_h; ++ih)
                for (int id = 0; id < g.n_theta_d; ++id) {
                    const std::size_t pixel = static_cast<std::size_t>(y0 + ih) * width + (x0 + id);
                    float* v = table.data() + 3 * g.index(ih, id, ip);
                    for (int c = 0; c < 3; ++c) v[c] = planes[c * plane + pixel];
                }
        }
        return table;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw FormatError(path, std::string("not a readable OpenEXR image: ") + e.what());
    }
}

}  // namespace brdfz::exr
