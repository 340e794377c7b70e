// Bounded scanning of small text formats (Cornell .brdf, ALTA .dat): the whole file is read once
// (its size bounded first), then walked line by line with line numbers for error messages.
// Numbers are parsed with std::from_chars: independent of the C locale a host program may have set.
#pragma once

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <string_view>

#include "brdfz/errors.h"

namespace brdfz::detail {

// The whole file as bytes. FormatError above max_bytes (checked before reading), IoError when the
// OS cannot read it.
inline std::string read_text_file(const std::string& path, std::uintmax_t max_bytes) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw IoError(path, "is a directory");
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(path, "cannot read: " + ec.message());
    if (size > max_bytes)
        throw FormatError(path, "file of " + std::to_string(size) + " bytes is larger than the " +
                                    std::to_string(max_bytes) + " this reader accepts");
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!f) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
    std::string text(static_cast<std::size_t>(size), '\0');
    if (std::fread(text.data(), 1, text.size(), f.get()) != text.size())
        throw IoError(path, "read failed (file changed while reading?)");
    return text;
}

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Lines of a text, numbered from 1; '\r' before '\n' is left to the tokenizer as white space.
class LineScanner {
public:
    explicit LineScanner(std::string_view text) : rest_(text) {}
    bool next(std::string_view& line) {
        if (done_) return false;
        const std::size_t end = rest_.find('\n');
        line = rest_.substr(0, end);
        ++number_;
        if (end == std::string_view::npos) {
            done_ = true;
            rest_ = {};
        } else {
            rest_.remove_prefix(end + 1);
        }
        return true;
    }
    std::size_t number() const { return number_; }

private:
    std::string_view rest_;
    std::size_t number_ = 0;
    bool done_ = false;
};

// Removes and returns the next white-space separated token of `line`; empty when there is none.
inline std::string_view next_token(std::string_view& line) {
    std::size_t b = 0;
    while (b < line.size() && is_space(line[b])) ++b;
    std::size_t e = b;
    while (e < line.size() && !is_space(line[e])) ++e;
    const std::string_view token = line.substr(b, e - b);
    line.remove_prefix(e);
    return token;
}

// The line without leading white space: "" for a blank line.
inline std::string_view trim_left(std::string_view line) {
    std::size_t b = 0;
    while (b < line.size() && is_space(line[b])) ++b;
    return line.substr(b);
}

// A token for an error message: printable ASCII only, at most 24 characters.
inline std::string quote(std::string_view token) {
    std::string out = "'";
    for (std::size_t k = 0; k < token.size() && k < 24; ++k) {
        const unsigned char c = static_cast<unsigned char>(token[k]);
        out += c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
    }
    return out + (token.size() > 24 ? "...'" : "'");
}

// A decimal floating-point number (also "inf", "nan"; one leading '+' allowed). Values beyond the
// double range become ±Inf, values below it ±0, as strtod would give. False if `token` is not
// entirely a number.
inline bool parse_double(std::string_view token, double& out) {
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    if (token.empty() || token[0] == '+') return false;
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, out);
    if (ptr != end) return false;
    if (ec == std::errc()) return true;
    if (ec != std::errc::result_out_of_range) return false;
    // from_chars leaves `out` unset when out of range: the decimal exponent of the first significant
    // digit tells overflow from underflow.
    const bool negative = token[0] == '-';
    long position = 0;  // power of ten of the first significant digit, plus one
    bool seen_point = false, seen_digit = false;
    std::size_t k = negative ? 1 : 0;
    for (; k < token.size() && token[k] != 'e' && token[k] != 'E'; ++k) {
        if (token[k] == '.') {
            seen_point = true;
        } else if (!seen_digit && token[k] == '0') {
            position -= seen_point;
        } else {
            seen_digit = true;
            position += !seen_point;
        }
    }
    long exponent = 0;
    if (k < token.size()) {
        const std::string_view e = token.substr(k + 1 + (k + 1 < token.size() && token[k + 1] == '+'));
        // An exponent too long for `long` is far outside the double range either way.
        if (std::from_chars(e.data(), e.data() + e.size(), exponent).ec != std::errc())
            exponent = e.starts_with('-') ? -100000 : 100000;
    }
    const double magnitude = position + exponent > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    out = negative ? -magnitude : magnitude;
    return true;
}

// A non-negative decimal integer token (digits only) no larger than `max`.
inline bool parse_count(std::string_view token, std::size_t max, std::size_t& out) {
    if (token.empty()) return false;
    for (char c : token)
        if (c < '0' || c > '9') return false;
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, out);
    return ec == std::errc() && ptr == end && out <= max;
}

}  // namespace brdfz::detail
