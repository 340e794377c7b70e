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

constexpr std::size_t kChunk = 1 << 15;  // bins per read: three planes stay in cache, no 35 MB buffer

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
    try {
        grid.validate();
    } catch (const ValueError& e) {
        throw FormatError(path, std::string("MERL dimensions: ") + e.what());
    }
    const std::uintmax_t n = grid.bins();
    const std::uintmax_t expected = kHeader + 3 * n * sizeof(double);
    if (size != expected)
        throw FormatError(path, std::string(size < expected ? "truncated" : "oversized") + " MERL file: " +
                                    std::to_string(size) + " bytes, dimensions " + grid.str() + " need " +
                                    std::to_string(expected));

    ReadResult result{Table(grid, Table::Uninitialized{}), {}};
    float* out = result.table.data();
    // The three planes are read side by side, chunk by chunk, so each bin's three channels are
    // classified and written together: sequential output, no per-bin flag array.
    std::vector<double> chunk(3 * std::min<std::uintmax_t>(kChunk, n));
    const std::size_t step = chunk.size() / 3;
    for (std::size_t start = 0; start < n; start += step) {
        const std::size_t count = std::min<std::size_t>(step, n - start);
        for (int c = 0; c < 3; ++c) {
            double* dst = chunk.data() + c * step;
            if (std::fseek(f.get(), static_cast<long>(kHeader + (c * n + start) * sizeof(double)), SEEK_SET) != 0 ||
                std::fread(dst, sizeof(double), count, f.get()) != count)
                throw IoError(path, "read failed (file changed while reading?)");
        }
        for (std::size_t k = 0; k < count; ++k) {
            float v[3];
            bool ok = true;
            for (int c = 0; c < 3; ++c) {
                const double raw = detail::from_little_endian(chunk[c * step + k]);
                v[c] = static_cast<float>(raw * kScale[c]);  // overflow to float Inf is caught below
                ok = ok && raw >= 0.0 && v[c] <= std::numeric_limits<float>::max();
            }
            float* o = out + 3 * (start + k);
            if (ok) {
                o[0] = v[0], o[1] = v[1], o[2] = v[2];
                ++result.counts.valid;
                continue;
            }
            // Rare: classify each channel, keep the valid ones.
            bool neg = false, nan = false, inf = false;
            for (int c = 0; c < 3; ++c) {
                const double raw = detail::from_little_endian(chunk[c * step + k]);
                const bool is_nan = std::isnan(raw), is_inf = !is_nan && std::isinf(v[c]), is_neg = !is_nan && raw < 0.0;
                nan |= is_nan, inf |= is_inf, neg |= is_neg;
                o[c] = is_nan || is_inf || is_neg ? std::numeric_limits<float>::quiet_NaN() : v[c];
            }
            result.counts.negative += neg;
            result.counts.nan += nan;
            result.counts.inf += inf;
        }
    }
    if (result.counts.valid == 0)
        throw FormatError(path, "no valid value in the MERL table (every bin is negative, NaN or Inf)");
    return result;
}

}  // namespace brdfz::merl
