// Checksums used by the .brdfz container (formats/SPEC.md):
//   CRC-32C (Castagnoli) guards every dataset against corruption; it runs at memory speed (SSE4.2
//   with three interleaved streams where available), so verifying costs little beside reading.
//   SHA-256 (FIPS 180-4) identifies content: source files, and files a container refers to.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "brdfz/runtime/crc32c.h"

namespace brdfz::container {

// CRC-32C is the runtime's (brdfz/runtime/crc32c.h): the runtime layout checks its files with it too.
using runtime::crc32c;

class Sha256 {
public:
    Sha256();
    void update(const void* data, std::size_t bytes);
    std::array<std::uint8_t, 32> finish();  // the object is spent afterwards

private:
    void block(const std::uint8_t* p);
    std::array<std::uint32_t, 8> h_;
    std::array<std::uint8_t, 64> buffer_{};
    std::size_t buffered_ = 0;
    std::uint64_t total_ = 0;
};

std::string hex(const std::array<std::uint8_t, 32>& digest);

// SHA-256 of a file's contents as 64 lowercase hex digits; IoError naming the file.
std::string sha256_file(const std::string& path);

}  // namespace brdfz::container
