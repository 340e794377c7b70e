// Deterministic pseudo-random numbers for fitting and the metrics over directions: the same on every
// platform and standard library (std::uniform_real_distribution is not), so starts, sample subsets and
// direction pairs are reproducible.
#pragma once

#include <cstdint>

namespace brdfz::detail {

// SplitMix64's finaliser: a bijective mix of 64 bits.
inline std::uint64_t mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

// A uniform number in [0, 1) determined by (index, seed).
inline double unit_hash(std::uint64_t index, std::uint64_t seed) {
    return static_cast<double>(mix64(index ^ mix64(seed)) >> 11) * 0x1.0p-53;
}

// A stream of uniform numbers in [0, 1).
class Random {
public:
    explicit Random(std::uint64_t seed) : state_(mix64(seed)) {}
    double uniform() { return static_cast<double>(mix64(state_++) >> 11) * 0x1.0p-53; }

private:
    std::uint64_t state_;
};

}  // namespace brdfz::detail
