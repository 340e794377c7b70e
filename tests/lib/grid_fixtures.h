// What the φd-symmetry tests (symmetry_test.cpp, bilateral_test.cpp) share: grids of a given symmetry,
// tables tabulated on them, metrics over directions, random directions, and a factored BRDF drawn
// through its factor sampler.
#pragma once

#include <cmath>
#include <random>
#include <string>

#include "brdfz/metrics.h"
#include "brdfz/repr/factored.h"
#include "brdfz/sample/factor_sampler.h"
#include "brdfz/table.h"
#include "brdfz/tabulate.h"

namespace brdfz::test {

inline GridSpec grid(int nh, int nd, int np, Symmetry s) {
    GridSpec g{nh, nd, np};
    g.symmetry = s;
    return g;
}

inline Table tabulated(const Brdf& b, const GridSpec& g) {
    TabulateOptions o;
    o.grid = g;
    return tabulate(b, o).table;
}

inline MetricOptions directions(std::size_t n = 1 << 16) {
    MetricOptions o;
    o.over = Over::Directions;
    o.directions = n;
    return o;
}

// A unit direction strictly above the horizon.
inline Vec3 random_upper(std::mt19937_64& rng) {
    std::normal_distribution<double> nd;
    Vec3 v = normalize({nd(rng), nd(rng), nd(rng)});
    v.z = std::fabs(v.z) + 1e-3;
    return normalize(v);
}

// A factored BRDF whose sample and pdf are its factor sampler's (FactoredBrdf samples half vectors).
struct FactorSampled final : Brdf {
    const FactoredBrdf& f;
    FactorSampler sampler;
    explicit FactorSampled(const FactoredBrdf& x) : f(x), sampler(x.factor_sampler()) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "factor-sampled"; }
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return f.eval(wi, wo); }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override { return sampler.sample(wo, u1, u2); }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return sampler.pdf(wo, wi); }
};

}  // namespace brdfz::test
