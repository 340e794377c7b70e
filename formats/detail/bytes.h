// Little-endian file values on any host.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

namespace brdfz::detail {

template <typename T>
T from_little_endian(T v) {
    if constexpr (std::endian::native == std::endian::little) {
        return v;
    } else {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        std::memcpy(&v, b, sizeof(T));
        return v;
    }
}

// The same swap both ways.
template <typename T>
T to_little_endian(T v) {
    return from_little_endian(v);
}

}  // namespace brdfz::detail
