#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/cornell.h"
#include "detail/horizon.h"
#include "detail/text_scan.h"

namespace brdfz::cornell {
namespace {

// Walks the file: checks the header and the shape of every record, and hands each record's numbers
// (θi φi θo φo, then the spectrum) with its line number to `on_record`. Returns the wavelengths.
// Run twice: once to count records before anything is allocated, once to store them.
template <typename OnRecord>
std::vector<double> scan(const std::string& path, std::string_view text, OnRecord&& on_record) {
    auto fail = [&](std::size_t line, const std::string& reason) -> FormatError {
        return FormatError(path, "line " + std::to_string(line) + ": " + reason);
    };
    detail::LineScanner lines(text);
    std::string_view line;
    std::size_t n = 0;  // declared wavelength count; 0 until read
    std::vector<double> wavelengths;
    std::vector<double> record;
    while (lines.next(line)) {
        const std::string_view content = detail::trim_left(line);
        if (content.empty() || content[0] == '#') continue;
        const std::size_t at = lines.number();
        if (n == 0) {
            const std::string_view token = detail::next_token(line);
            if (!detail::parse_count(token, kMaxWavelengths, n) || n < 2)
                throw fail(at, "expected the number of wavelengths (an integer, 2.." + std::to_string(kMaxWavelengths) +
                                   "), found " + detail::quote(token));
            if (!detail::next_token(line).empty()) throw fail(at, "more than one number on the wavelength-count line");
            wavelengths.reserve(n);  // bounded by kMaxWavelengths
            continue;
        }
        if (wavelengths.size() < n) {
            for (std::string_view token = detail::next_token(line); !token.empty(); token = detail::next_token(line)) {
                double nm = 0;
                if (wavelengths.size() == n)
                    throw fail(at, "more wavelengths than the " + std::to_string(n) + " declared");
                if (!detail::parse_double(token, nm) || !std::isfinite(nm))
                    throw fail(at, "expected a wavelength in nm, found " + detail::quote(token));
                if (!wavelengths.empty() && !(nm > wavelengths.back()))
                    throw fail(at, "wavelengths must increase strictly (" + detail::quote(token) + " follows " +
                                       std::to_string(wavelengths.back()) + ")");
                if (nm < kMinWavelength || nm > kMaxWavelength)
                    throw UnsupportedError(path, "line " + std::to_string(at) + ": wavelength " + detail::quote(token) +
                                                     " nm is outside the 380..780 nm of the colour matching functions");
                wavelengths.push_back(nm);
            }
            continue;
        }
        record.clear();
        for (std::string_view token = detail::next_token(line); !token.empty(); token = detail::next_token(line)) {
            if (record.size() == 4 + n)
                throw fail(at, "more than the " + std::to_string(4 + n) + " numbers of a record (4 angles, " +
                                   std::to_string(n) + " spectral values)");
            double v = 0;
            if (!detail::parse_double(token, v)) throw fail(at, "expected a number, found " + detail::quote(token));
            record.push_back(v);
        }
        if (record.size() != 4 + n)
            throw fail(at, "a record needs " + std::to_string(4 + n) + " numbers (4 angles, " + std::to_string(n) +
                               " spectral values), found " + std::to_string(record.size()));
        for (int k = 0; k < 4; ++k)
            if (!std::isfinite(record[k])) throw fail(at, "angle " + std::to_string(k + 1) + " is not finite");
        for (int k : {0, 2})
            if (record[k] < 0.0 || record[k] > std::numbers::pi)
                throw fail(at, "polar angle " + std::to_string(record[k]) + " outside [0, pi]");
        on_record(at, std::span<const double>(record));
    }
    if (n == 0) throw FormatError(path, "no wavelength count (not a Cornell .brdf file?)");
    if (wavelengths.size() < n)
        throw FormatError(path, "file ends after " + std::to_string(wavelengths.size()) + " of the " +
                                    std::to_string(n) + " wavelengths");
    return wavelengths;
}

}  // namespace

ReadResult read(const std::string& path) {
    const std::string text = detail::read_text_file(path, kMaxFileBytes);

    ReadResult result;
    result.wavelengths = scan(path, text, [&](std::size_t line, std::span<const double>) {
        if (++result.records > kMaxRecords)
            throw FormatError(path, "line " + std::to_string(line) + ": more than " + std::to_string(kMaxRecords) +
                                        " records");
    });
    if (result.records == 0) throw FormatError(path, "no measurement records after the wavelengths");

    std::vector<Rgb> weights;
    try {
        weights = rgb_weights(result.wavelengths);
    } catch (const ValueError& e) {
        throw UnsupportedError(path, e.what());
    }

    MeasurementSet& set = result.set;
    set.channels = 3;
    set.source = path;
    set.samples.reserve(result.records);
    ValidityCounts& counts = result.counts;
    scan(path, text, [&](std::size_t, std::span<const double> r) {
        const Vec3 wi = spherical_direction(r[0], r[1]);
        const Vec3 wo = spherical_direction(r[2], r[3]);
        if (!detail::above_horizon(wi) || !detail::above_horizon(wo)) {
            ++counts.below_horizon;
            return;
        }
        const std::span<const double> spectrum = r.subspan(4);
        bool nan = false, inf = false, negative_spectral = false;
        Rgb f{};
        for (std::size_t k = 0; k < spectrum.size(); ++k) {
            nan = nan || std::isnan(spectrum[k]);
            inf = inf || std::isinf(spectrum[k]);
            negative_spectral = negative_spectral || spectrum[k] < 0.0;
            for (int c = 0; c < 3; ++c) f[c] += weights[k][c] * spectrum[k];
        }
        // Finite spectra can still overflow in the weighted sum.
        inf = inf || (!nan && !(std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2])));
        counts.nan += nan;
        counts.inf += inf;
        if (nan || inf) return;
        result.negative_spectral += negative_spectral;
        if (f[0] < 0.0 || f[1] < 0.0 || f[2] < 0.0)
            ++counts.negative;
        else
            ++counts.valid;
        set.samples.push_back({wi, wo, f});
    });
    if (set.samples.empty())
        throw FormatError(path, "no usable record: all " + std::to_string(result.records) +
                                    " are below the horizon or not finite");
    return result;
}

}  // namespace brdfz::cornell
