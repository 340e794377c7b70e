// The kernels' levels (brdfz/simd.h): what the CPU runs, and its name. scripts/test-arm64 runs this on
// emulated CPUs with BRDFZ_EXPECT_SIMD set to the level each one must get.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <string>

#include "brdfz/simd.h"
#include "simd_levels.h"

using namespace brdfz;

TEST_CASE("simd: the levels the CPU runs, their names, and the one BRDFZ_EXPECT_SIMD names", "[simd][kernels][qemu]") {
    const auto levels = test::simd_levels();
    REQUIRE(!levels.empty());
    CHECK(levels.front() == detail::Simd::Sse2);
    CHECK(levels.back() == simd_level());
    // Capped, the level and its name follow the cap.
    for (detail::Simd s : levels) {
        test::SimdCap cap(s);
        CHECK(simd_level() == s);
    }
    const std::string name = simd_name();
#if BRDFZ_X86
    CHECK((name == "sse2" || name == "avx2" || name == "avx512"));
    CHECK((name == "avx2") == (simd_level() == detail::Simd::Avx2Fma));
    CHECK(runtime::kernels::cpu_has_sse4() == (__builtin_cpu_supports("sse4.2") != 0));
#elif defined(__aarch64__)
    CHECK((name == "neon" || name == "sve" || name == "sve2"));
    CHECK((name == "sve") == (simd_level() == detail::Simd::Sve));
#endif
    if (const char* expected = std::getenv("BRDFZ_EXPECT_SIMD")) CHECK(name == expected);
}
