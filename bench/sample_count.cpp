// Instruction counts of the tabular sampler (the fine, half-vector one) under valgrind (robust to the machine's load, unlike the
// wall clock of bench/sample):
//   valgrind --tool=callgrind --toggle-collect='measured_*' build/bench/sample_count FILE [N]
// then callgrind_annotate: each measured_* function's inclusive count divided by N is its cost per
// sample. N random wo (uniform on the hemisphere) and u; the sampler is built before measuring.
//   measured_sample: Brdf::sample(span), the whole sample including its weight
//   measured_sample_one: Brdf::sample(wo, u1, u2), the same one call at a time (a renderer's use)
//   measured_draw:   the sampler's own sample() (direction and pdf), one at a time
//   measured_draw_block: the same draws in blocks (HalfVectorSampler::draw_block, as sample() draws)
//   measured_eval:   Brdf::eval(span) at the drawn pairs (the weight's lookup alone)
//   measured_eval_one: Brdf::eval(wi, wo) at the same pairs, one call at a time
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <exception>
#include <cstdlib>
#include <random>
#include <vector>

#include "brdfz/formats/io.h"
#include "brdfz/repr/tabular.h"

using namespace brdfz;

extern "C" {
[[gnu::noinline]] double measured_sample(const Brdf& b, const std::vector<Vec3>& wo,
                                         const std::vector<std::array<double, 2>>& u, std::vector<BrdfSample>& out) {
    b.sample(wo, u, out);
    return out[0].pdf;
}
[[gnu::noinline]] double measured_sample_one(const Brdf& b, const std::vector<Vec3>& wo,
                                             const std::vector<std::array<double, 2>>& u, std::vector<BrdfSample>& out) {
    for (std::size_t k = 0; k < wo.size(); ++k) out[k] = b.sample(wo[k], u[k][0], u[k][1]);
    return out[0].pdf;
}
[[gnu::noinline]] double measured_draw(const HalfVectorSampler& s, const std::vector<Vec3>& wo,
                                       const std::vector<std::array<double, 2>>& u, std::vector<BrdfSample>& out) {
    for (std::size_t k = 0; k < wo.size(); ++k) out[k] = s.sample(wo[k], u[k][0], u[k][1]);
    return out[0].pdf;
}
[[gnu::noinline]] double measured_draw_block(const HalfVectorSampler& s, const std::vector<Vec3>& wo,
                                             const std::vector<std::array<double, 2>>& u) {
    HalfVectorSampler::Draws block;
    double check = 0.0;
    for (std::size_t start = 0; start < wo.size(); start += HalfVectorSampler::kBlock) {
        const std::size_t m = std::min(HalfVectorSampler::kBlock, wo.size() - start);
        s.draw_block(wo.data() + start, u.data() + start, m, block);
        check += block.pdf[0];
    }
    return check;
}
[[gnu::noinline]] double measured_eval(const Brdf& b, const std::vector<Vec3>& wi, const std::vector<Vec3>& wo,
                                       std::vector<Rgb>& f) {
    b.eval(wi, wo, f);
    return f[0][0];
}
[[gnu::noinline]] double measured_eval_one(const Brdf& b, const std::vector<Vec3>& wi, const std::vector<Vec3>& wo,
                                           std::vector<Rgb>& f) {
    for (std::size_t k = 0; k < wi.size(); ++k) f[k] = b.eval(wi[k], wo[k]);
    return f[0][0];
}
}

int main(int argc, char** argv) try {
    if (argc < 2) {
        std::fprintf(stderr, "usage: sample_count FILE [N]\n");
        return 2;
    }
    const std::size_t n = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 16384;
    LoadOptions fine;
    fine.sampler = SamplerKind::Fine;
    const Loaded l = load(argv[1], fine);
    const auto* t = dynamic_cast<const TabularBrdf*>(l.brdf.get());
    if (!t || n == 0) {
        std::fprintf(stderr, "sample_count: %s is not a table, or N is 0\n", argv[1]);
        return 2;
    }
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    std::vector<std::array<double, 2>> u(n);
    std::vector<Vec3> wo(n), wi(n);
    for (std::size_t k = 0; k < n; ++k) {
        u[k] = {u01(rng), u01(rng)};
        const double z = u01(rng), r = std::sqrt(1.0 - z * z), phi = 2.0 * M_PI * u01(rng);
        wo[k] = {r * std::cos(phi), r * std::sin(phi), z};
    }
    const HalfVectorSampler& sampler = *t->sampler().fine();  // built at load, outside the measured calls
    std::vector<BrdfSample> out(n), drawn(n);
    std::vector<Rgb> f(n);
    double check = measured_sample(*t, wo, u, out);
    check += measured_sample_one(*t, wo, u, out);
    check += measured_draw(sampler, wo, u, drawn);
    check += measured_draw_block(sampler, wo, u);
    for (std::size_t k = 0; k < n; ++k) wi[k] = drawn[k].pdf > 0 ? drawn[k].wi : Vec3{0, 0, 1};
    check += measured_eval(*t, wi, wo, f);
    check += measured_eval_one(*t, wi, wo, f);
    std::printf("%zu samples [%g]\n", n, check);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "sample_count: %s\n", e.what());
    return 1;
}
