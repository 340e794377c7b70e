// Standard CRC-32C (Castagnoli; initial value and final xor 0xFFFFFFFF, reflected): crc32c("123456789")
// == 0xE3069283. Chain calls by passing the previous result as `crc`. At memory speed where the CPU has
// a crc32 instruction (SSE4.2), table-driven elsewhere.
#pragma once

#include <cstddef>
#include <cstdint>

namespace brdfz::runtime {

std::uint32_t crc32c(const void* data, std::size_t bytes, std::uint32_t crc = 0);

}  // namespace brdfz::runtime
