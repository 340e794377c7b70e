// Typed exceptions thrown by the library. Library code never prints or exits; the CLI catches these
// in main and prints what() as one line, and Python maps them to ValueError / OSError.
#pragma once

#include <stdexcept>
#include <string>

namespace brdfz {

// Base of every brdfz exception.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
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

}  // namespace brdfz
