// Typed exceptions thrown by the library. Library code never prints or exits; the CLI catches these
// in main and prints what() as one line, and Python maps them to ValueError / OSError.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace brdfz {

// `text` with every byte that is not printable valid UTF-8 (control characters, C1 controls, stray
// or overlong bytes) written as \xNN: messages quote names and bytes read from files, and must stay
// one line on a terminal and valid text for Python.
inline std::string printable(std::string_view text) {
    const auto cont = [&](std::size_t i, unsigned char lo = 0x80, unsigned char hi = 0xbf) {
        return i < text.size() && static_cast<unsigned char>(text[i]) >= lo && static_cast<unsigned char>(text[i]) <= hi;
    };
    std::string out;
    for (std::size_t i = 0; i < text.size();) {
        const auto c = static_cast<unsigned char>(text[i]);
        std::size_t n = 0;  // length of a valid, printable sequence starting here
        if (c >= 0x20 && c < 0x7f) n = 1;
        else if (c == 0xc2) n = cont(i + 1, 0xa0) ? 2 : 0;  // not U+0080..U+009F (C1 controls)
        else if (c > 0xc2 && c <= 0xdf) n = cont(i + 1) ? 2 : 0;
        else if (c >= 0xe0 && c <= 0xef)
            n = cont(i + 1, c == 0xe0 ? 0xa0 : 0x80, c == 0xed ? 0x9f : 0xbf) && cont(i + 2) ? 3 : 0;
        else if (c >= 0xf0 && c <= 0xf4)
            n = cont(i + 1, c == 0xf0 ? 0x90 : 0x80, c == 0xf4 ? 0x8f : 0xbf) && cont(i + 2) && cont(i + 3) ? 4 : 0;
        if (n) {
            out.append(text, i, n);
            i += n;
        } else {
            static constexpr char kHex[] = "0123456789abcdef";
            out += {'\\', 'x', kHex[c >> 4], kHex[c & 15]};
            ++i;
        }
    }
    return out;
}

// Base of every brdfz exception; its message is printable() text.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(printable(what)) {}
};

// A file that cannot be read or written at the operating-system level (missing, permissions, disk).
class IoError : public Error {
public:
    IoError(const std::string& path, const std::string& reason) : Error(path + ": " + reason) {}
};

// A file whose contents are not a valid instance of its format (truncated, wrong sizes, corrupt).
class FormatError : public Error {
public:
    FormatError(const std::string& path, const std::string& reason) : Error(path + ": " + reason) {}
};

// A valid file or argument that this library does not handle (e.g. anisotropic RGL data).
class UnsupportedError : public Error {
public:
    UnsupportedError(const std::string& path, const std::string& reason) : Error(path + ": " + reason) {}
};

// An argument outside its domain (mismatched batch sizes, zero resolution, NaN parameter, ...).
class ValueError : public Error {
public:
    using Error::Error;
};

// A representation spec that does not parse, or names an unknown kind or option (repr/spec.h): the
// caller's mistake, which the budget-driven selection reports instead of counting it a failed candidate.
class SpecError : public ValueError {
public:
    using ValueError::ValueError;
};

}  // namespace brdfz
