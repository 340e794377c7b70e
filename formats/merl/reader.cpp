#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/merl.h"
#include "detail/bytes.h"

namespace brdfz::merl {
namespace {

// Per-bin classification flags gathered across the three planes.
enum : std::uint8_t { kNegative = 1, kNan = 2, kInf = 4 };

constexpr std::size_t kChunk = 1 << 16;  // doubles per read: streams through cache, no 35 MB buffer

}  // namespace

ReadResult read(const std::string& path, BinPosition position) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(path, "cannot read: " + ec.message());

    constexpr std::uintmax_t kHeader = 3 * sizeof(std::int32_t);
    if (size < kHeader)
        throw FormatError(path, "truncated MERL file: " + std::to_string(size) + " bytes, the header alone needs 12");

    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!f) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));

    std::int32_t dims[3];
    if (std::fread(dims, sizeof dims, 1, f.get()) != 1) throw IoError(path, "cannot read the header");
    for (auto& d : dims) d = detail::from_little_endian(d);
    for (std::int32_t d : dims)
        if (d < 1 || d > GridSpec::kMaxAxis)
            throw FormatError(path, "MERL dimensions " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                                        std::to_string(dims[2]) + " out of range (each must be 1.." +
                                        std::to_string(GridSpec::kMaxAxis) + ")");

    const GridSpec grid{dims[0], dims[1], dims[2], position};
    const std::uintmax_t n = grid.bins();
    const std::uintmax_t expected = kHeader + 3 * n * sizeof(double);
    if (size != expected)
        throw FormatError(path, std::string(size < expected ? "truncated" : "oversized") + " MERL file: " +
                                    std::to_string(size) + " bytes, dimensions " + grid.str() + " need " +
                                    std::to_string(expected));

    ReadResult result{Table(grid), {}};
    float* out = result.table.data();
    std::vector<std::uint8_t> flags(n, 0);
    std::vector<double> chunk(std::min<std::uintmax_t>(kChunk, n));
    for (int c = 0; c < 3; ++c) {
        for (std::size_t start = 0; start < n; start += chunk.size()) {
            const std::size_t count = std::min<std::size_t>(chunk.size(), n - start);
            if (std::fread(chunk.data(), sizeof(double), count, f.get()) != count)
                throw IoError(path, "read failed (file changed while reading?)");
            for (std::size_t k = 0; k < count; ++k) {
                const double raw = detail::from_little_endian(chunk[k]);
                const float v = static_cast<float>(raw * kScale[c]);  // overflow to float Inf is caught below
                const std::uint8_t cls = std::isnan(raw) ? kNan : std::isinf(v) ? kInf : raw < 0.0 ? kNegative : 0;
                flags[start + k] |= cls;
                out[3 * (start + k) + c] = cls ? std::numeric_limits<float>::quiet_NaN() : v;
            }
        }
    }
    for (std::uint8_t fl : flags) {
        result.counts.valid += fl == 0;
        result.counts.negative += (fl & kNegative) != 0;
        result.counts.nan += (fl & kNan) != 0;
        result.counts.inf += (fl & kInf) != 0;
    }
    if (result.counts.valid == 0)
        throw FormatError(path, "no valid value in the MERL table (every bin is negative, NaN or Inf)");
    return result;
}

}  // namespace brdfz::merl
