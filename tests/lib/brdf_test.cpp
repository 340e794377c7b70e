// Brdf's batch calls (lib/src/brdf.cpp): whatever mix of directions a long batch holds, it gives the bits
// of one call at a time.
#include <catch2/catch.hpp>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/repr/analytic/model.h"
#include "sample_stats.h"

using namespace brdfz;

TEST_CASE("brdf: a batch over several slices, unit directions in some and not in others, gives one call's bits",
          "[brdf][batch]") {
    // The batch calls check and run their kernels a slice of 4096 pairs at a time: three slices and a bit,
    // the second with directions to prepare (scaled, zero, NaN, infinite), the others all unit.
    const std::size_t n = 3 * 4096 + 123;
    auto [wo, u] = test::random_views(n, 31);
    auto [wi, unused] = test::random_views(n, 32);
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (std::size_t k = 4096; k < 2 * 4096; k += 7) {
        wi[k] = 2.5 * wi[k];
        wo[k + 3] = 0.25 * wo[k + 3];
    }
    wi[4096 + 100] = {0.0, 0.0, 0.0};
    wo[4096 + 200] = {nan, 0.0, 1.0};
    wi[2 * 4096 - 1] = {0.0, inf, 1.0};
    const AnalyticBrdf analytic("lambert+ggx", {0.3, 0.25, 0.2, 0.6, 0.6, 0.6, 0.3, 0.04});
    // The default batch kernels, the factored ones and the table ones.
    const Compressed factored = compress(analytic, "svd:rank=2,res=16x16x32");
    const Compressed table = compress(analytic, "tabular:res=16x16x32");
    for (const Brdf* b : std::initializer_list<const Brdf*>{&analytic, factored.brdf.get(), table.brdf.get()}) {
        std::vector<Rgb> f(n), fc(n);
        std::vector<double> p(n);
        std::vector<BrdfSample> s(n);
        b->eval(std::span<const Vec3>(wi), std::span<const Vec3>(wo), std::span(f));
        b->eval_cos(std::span<const Vec3>(wi), std::span<const Vec3>(wo), std::span(fc));
        b->pdf(std::span<const Vec3>(wo), std::span<const Vec3>(wi), std::span(p));
        b->sample(std::span<const Vec3>(wo), std::span<const std::array<double, 2>>(u), std::span(s));
        std::size_t differ[3] = {0, 0, 0}, nonzero = 0;
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t slice = k / 4096 == 1 ? 1 : 0;
            differ[slice] += !test::same_bits(f[k], b->eval(wi[k], wo[k]));
            differ[slice] += !test::same_bits(fc[k], b->eval_cos(wi[k], wo[k]));
            differ[slice] += !test::same_bits(p[k], b->pdf(wo[k], wi[k]));
            differ[slice] += !test::same_bits(s[k], b->sample(wo[k], u[k][0], u[k][1]));
            nonzero += (k / 4096 == 1) && (k % 7 == 0) && f[k][0] > 0.0;
        }
        CHECK(differ[0] == 0);
        CHECK(differ[1] == 0);
        CHECK(nonzero > 200);  // the scaled directions are evaluated, not refused
        for (std::size_t k : {std::size_t{4096 + 100}, std::size_t{4096 + 200}, std::size_t{2 * 4096 - 1}}) {
            CHECK(f[k] == Rgb{0.0, 0.0, 0.0});
            CHECK(p[k] == 0.0);
        }
        CHECK(s[4096 + 200].pdf == 0.0);
    }
}
