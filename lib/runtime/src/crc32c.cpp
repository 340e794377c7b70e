// CRC-32C (Castagnoli): the runtime layout's checksum and the .brdfz container's (formats/SPEC.md).
#include "brdfz/runtime/crc32c.h"

#include <array>
#include <cstring>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <nmmintrin.h>
#define BRDFZ_CRC32C_SSE42 1
#endif

namespace brdfz::runtime {
namespace {

constexpr std::uint32_t kPoly = 0x82F63B78u;  // Castagnoli polynomial, bit-reversed

constexpr std::array<std::uint32_t, 256> make_table() {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
        std::uint32_t c = i;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (c & 1 ? kPoly : 0);
        t[i] = c;
    }
    return t;
}
constexpr std::array<std::uint32_t, 256> kTable = make_table();

// The CRC register (no initial value or final xor applied here) fed with bytes.
std::uint32_t update_bytes(std::uint32_t state, const unsigned char* p, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) state = (state >> 8) ^ kTable[(state ^ p[k]) & 0xFF];
    return state;
}

#ifdef BRDFZ_CRC32C_SSE42
// Polynomials over GF(2) modulo P in the reflected representation (bit 31 holds x^0). The register
// is linear in its input, so the state after A‖B equals state(A)·x^(8|B|) xor the state of B alone
// from zero: three independent streams can run side by side and be joined exactly.
constexpr std::uint32_t gf2_mul(std::uint32_t a, std::uint32_t b) {
    std::uint32_t product = 0;
    for (int i = 0; i < 32; ++i) {
        if (a & (0x80000000u >> i)) product ^= b;
        b = (b >> 1) ^ (b & 1 ? kPoly : 0);  // b·x
    }
    return product;
}
// x^(8n) mod P: the effect of n zero bytes on the register.
constexpr std::uint32_t shift_of(std::uint64_t n) {
    std::uint32_t result = 0x80000000u, base = 0x00800000u;  // x^0, x^8
    for (; n; n >>= 1, base = gf2_mul(base, base))
        if (n & 1) result = gf2_mul(result, base);
    return result;
}

// One lane length of the three-stream loop: long enough that joining costs nothing, short enough
// that the three read positions stay within the same few pages.
constexpr std::size_t kLane = 8192;
constexpr std::uint32_t kShiftLane = shift_of(kLane), kShiftTwoLanes = shift_of(2 * kLane);

__attribute__((target("sse4.2"))) std::uint32_t update_sse42(std::uint32_t state, const unsigned char* p,
                                                              std::size_t n) {
    const auto load = [](const unsigned char* q) {
        std::uint64_t v;
        std::memcpy(&v, q, 8);
        return v;
    };
    // The crc32 instruction has a latency of three cycles and a throughput of one: three streams.
    for (; n >= 3 * kLane; p += 3 * kLane, n -= 3 * kLane) {
        std::uint64_t a = state, b = 0, c = 0;
        for (std::size_t i = 0; i < kLane; i += 8) {
            a = _mm_crc32_u64(a, load(p + i));
            b = _mm_crc32_u64(b, load(p + kLane + i));
            c = _mm_crc32_u64(c, load(p + 2 * kLane + i));
        }
        state = gf2_mul(static_cast<std::uint32_t>(a), kShiftTwoLanes) ^
                gf2_mul(static_cast<std::uint32_t>(b), kShiftLane) ^ static_cast<std::uint32_t>(c);
    }
    std::uint64_t s = state;
    for (; n >= 8; p += 8, n -= 8) s = _mm_crc32_u64(s, load(p));
    state = static_cast<std::uint32_t>(s);
    for (; n; ++p, --n) state = _mm_crc32_u8(state, *p);
    return state;
}

bool have_sse42() {
    static const bool yes = __builtin_cpu_supports("sse4.2");
    return yes;
}
#endif

}  // namespace

std::uint32_t crc32c(const void* data, std::size_t bytes, std::uint32_t crc) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint32_t state = ~crc;
#ifdef BRDFZ_CRC32C_SSE42
    if (have_sse42()) return ~update_sse42(state, p, bytes);
#endif
    return ~update_bytes(state, p, bytes);
}

}  // namespace brdfz::runtime
