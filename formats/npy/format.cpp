// NumPy .npy tables: a Rusinkiewicz table as the array numpy.load returns, float32 of shape
// (nθh, nθd, nφd, 3) in C order, f_r in 1/sr with NaN for invalid entries — the layout of Table and of
// Python's Brdf.table — on MERL's axes (square-root θh, linear θd, φd over [0, π)). The NPY format
// (versions 1-3) is numpy's own (numpy.lib.format); only little-endian float32 and float64 arrays in
// C order are read, and float32 is written (version 1.0, header padded to 64 bytes).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/formats/registry.h"
#include "brdfz/repr/tabular.h"
#include "detail/atomic_file.h"
#include "detail/bytes.h"
#include "detail/examples.h"
#include "detail/table_io.h"

namespace brdfz::formats {
namespace {

constexpr std::string_view kMagic{"\x93NUMPY", 6};
constexpr std::size_t kMaxHeader = 1 << 16;

// The value after 'key': in a header dict, up to the next top-level ',' or '}' (a tuple whole).
std::string_view dict_value(std::string_view header, std::string_view key, const std::string& path) {
    std::string quoted(1, '\'');
    quoted.append(key).push_back('\'');
    std::size_t at = header.find(quoted);
    if (at == std::string_view::npos) throw FormatError(path, "NPY header has no " + quoted);
    at = header.find(':', at + quoted.size());
    if (at == std::string_view::npos) throw FormatError(path, "NPY header: no value for " + quoted);
    std::size_t start = header.find_first_not_of(' ', at + 1), end = start;
    if (start == std::string_view::npos) throw FormatError(path, "NPY header: no value for " + quoted);
    if (header[start] == '(') {
        end = header.find(')', start);
        if (end == std::string_view::npos) throw FormatError(path, "NPY header: unterminated shape");
        return header.substr(start + 1, end - start - 1);
    }
    end = header.find_first_of(",}", start);
    if (end == std::string_view::npos) throw FormatError(path, "NPY header: unterminated " + quoted);
    return header.substr(start, end - start);
}

std::vector<std::uint64_t> parse_shape(std::string_view text, const std::string& path) {
    std::vector<std::uint64_t> dims;
    std::size_t pos = 0;
    while (pos < text.size()) {
        pos = text.find_first_not_of(" ,", pos);
        if (pos == std::string_view::npos) break;
        std::uint64_t n = 0;
        const auto [end, ec] = std::from_chars(text.data() + pos, text.data() + text.size(), n);
        if (ec != std::errc()) throw FormatError(path, "NPY header: shape (" + std::string(text) + ") is not a tuple of sizes");
        dims.push_back(n);
        pos = static_cast<std::size_t>(end - text.data());
    }
    return dims;
}

Loaded read(const std::string& path, const LoadOptions& options) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(path, "cannot read: " + ec.message());
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, "cannot open");
    char start[12] = {};
    in.read(start, 10);
    if (in.gcount() != 10 || std::string_view(start, 6) != kMagic) throw FormatError(path, "not an NPY file (no \\x93NUMPY magic)");
    const int major = static_cast<unsigned char>(start[6]);
    std::uint64_t header_len = 0, offset = 10;
    if (major == 1) {
        header_len = static_cast<unsigned char>(start[8]) | (static_cast<unsigned char>(start[9]) << 8);
    } else if (major == 2 || major == 3) {
        in.read(start + 10, 2);
        if (in.gcount() != 2) throw FormatError(path, "truncated NPY header");
        std::uint32_t n;
        std::memcpy(&n, start + 8, 4);
        header_len = detail::from_little_endian(n);
        offset = 12;
    } else {
        throw UnsupportedError(path, "NPY version " + std::to_string(major) + " (1 to 3 are read)");
    }
    if (header_len > kMaxHeader || offset + header_len > size)
        throw FormatError(path, "NPY header of " + std::to_string(header_len) + " bytes does not fit the file");
    std::string header(header_len, '\0');
    in.read(header.data(), static_cast<std::streamsize>(header_len));
    if (static_cast<std::uint64_t>(in.gcount()) != header_len) throw FormatError(path, "truncated NPY header");

    const std::string_view descr = dict_value(header, "descr", path);
    const bool f64 = descr == "'<f8'";
    if (!f64 && descr != "'<f4'")
        throw UnsupportedError(path, "NPY dtype " + std::string(descr) + " (little-endian float32 or float64 tables are read)");
    if (dict_value(header, "fortran_order", path) != "False")
        throw UnsupportedError(path, "NPY array in Fortran order (save it with numpy in C order)");
    const std::vector<std::uint64_t> shape = parse_shape(dict_value(header, "shape", path), path);
    if (shape.size() != 4 || shape[3] != 3)
        throw FormatError(path, "NPY shape must be (θh, θd, φd, 3), a table of RGB values");
    for (int k = 0; k < 3; ++k)
        if (shape[k] < 1 || shape[k] > static_cast<std::uint64_t>(GridSpec::kMaxAxis))
            throw FormatError(path, "NPY table axis of " + std::to_string(shape[k]) + " bins (1.." +
                                        std::to_string(GridSpec::kMaxAxis) + ")");
    const GridSpec grid{static_cast<int>(shape[0]), static_cast<int>(shape[1]), static_cast<int>(shape[2]),
                        options.position};
    grid.validate();
    const std::uint64_t item = f64 ? 8 : 4, values = 3 * grid.bins();
    if (size != offset + header_len + values * item)
        throw FormatError(path, "NPY data of " + std::to_string(size - offset - header_len) + " bytes, the shape needs " +
                                    std::to_string(values * item));

    Table table(grid, Table::Uninitialized{});
    ValidityCounts counts;
    std::vector<char> chunk(3 * item * 4096);
    float* out = table.data();
    for (std::size_t bin = 0; bin < grid.bins();) {
        const std::size_t n = std::min<std::size_t>(4096, grid.bins() - bin);
        in.read(chunk.data(), static_cast<std::streamsize>(3 * item * n));
        if (static_cast<std::size_t>(in.gcount()) != 3 * item * n) throw IoError(path, "read failed (file changed while reading?)");
        for (std::size_t k = 0; k < n; ++k, ++bin) {
            bool neg = false, nan = false, inf = false;
            for (int c = 0; c < 3; ++c) {
                double v;
                if (f64) {
                    std::memcpy(&v, chunk.data() + 8 * (3 * k + c), 8);
                    v = detail::from_little_endian(v);
                } else {
                    float w;
                    std::memcpy(&w, chunk.data() + 4 * (3 * k + c), 4);
                    v = detail::from_little_endian(w);
                }
                const bool is_nan = std::isnan(v), is_inf = std::fabs(v) > std::numeric_limits<float>::max() && !is_nan;
                const bool is_neg = !is_nan && !is_inf && v < 0.0;
                nan |= is_nan, inf |= is_inf, neg |= is_neg;
                out[3 * bin + c] = is_nan || is_inf || is_neg ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v);
            }
            // NaN is how the table marks an unmeasured entry: counted as invalid, not as a defect.
            if (!neg && !inf && !nan) ++counts.valid;
            counts.negative += neg;
            counts.inf += inf;
            counts.nan += nan;
        }
    }
    if (counts.valid == 0) throw FormatError(path, "no valid value in the NPY table (every bin is negative, NaN or Inf)");
    Loaded loaded;
    loaded.info = detail::table_info("npy", table, counts);
    loaded.brdf = std::make_unique<TabularBrdf>(std::move(table), options.lookup, options.sampler);
    return loaded;
}

void write_table(const std::string& path, const Table& table) {
    const GridSpec& g = table.grid();
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(g.n_theta_h) + ", " +
                         std::to_string(g.n_theta_d) + ", " + std::to_string(g.n_phi_d) + ", 3), }";
    header.append(63 - (kMagic.size() + 4 + header.size()) % 64, ' ');
    header += '\n';
    const std::uint16_t len = detail::to_little_endian(static_cast<std::uint16_t>(header.size()));
    detail::AtomicFile file(path);
    file.write(kMagic.data(), kMagic.size());
    file.write("\x01\x00", 2);
    file.write(&len, 2);
    file.write(header.data(), header.size());
    if constexpr (std::endian::native == std::endian::little) {
        file.write(table.data(), 3 * table.bins() * sizeof(float));
    } else {
        for (std::size_t k = 0; k < 3 * table.bins(); ++k) {
            const float v = detail::to_little_endian(table.data()[k]);
            file.write(&v, sizeof v);
        }
    }
    file.commit();
}

ValidityCounts write(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    return detail::save_table(brdf, options, [&](const Table& t) { write_table(path, t); });
}

bool sniff(std::string_view head, std::uintmax_t) { return head.substr(0, kMagic.size()) == kMagic; }

void examples(const std::string& dir) {
    write_table(dir + "/a.npy", detail::example_table({2, 3, 4}));
    write_table(dir + "/b.npy", detail::example_table({5, 1, 1}));
}

}  // namespace

void register_npy(std::vector<Format>& out) {
    out.push_back({"npy", "NumPy array of a table, float32 (θh, θd, φd, 3), NaN invalid (numpy.load reads it)", {".npy"},
                   sniff, read, nullptr, write, examples});
}

}  // namespace brdfz::formats
