// The factor sampler (sample/factor_sampler.h) against the half-vector sampler on the same factored BRDF:
// build time, variance of the directional-albedo estimate at equal sample counts, and sampling speed.
//
// Usage: factor_sample [--spec SPEC]... [FILE.binary...]
// Without files the 90x90x180 table is synthetic (bench/common.h). Default specs: nmf and svd in linear
// space, svd in log space, nmf in cbrt space. Every estimator weights by the same f (the factored BRDF's
// eval): only the density the directions are drawn from differs.
// Variance: of one sample's albedo contribution f·cosθi/pdf (mean channel), n = 10^6 per θo, same seed.
// Factor sampler: both densities (FactorDensity::Marginal, the default, and Mixture, Lawrence's).
// Build: single thread, median of 5 (factor) and 3 (half-vector, threads = 1).
// Speed: batch sample() including the weight's eval, and the sampler's draw alone (one at a time, no
// weight), one core, median of 7 over 2^20 draws.
#include <array>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/sample/factor_sampler.h"
#include "brdfz/sample/halfvector.h"
#include "common.h"

using namespace brdfz;

namespace {

// A Brdf evaluating `b` and sampling with sampler S (or cosine-weighted when null).
template <typename S>
class SampledWith final : public Brdf {
public:
    SampledWith(const Brdf& b, const S* s) : b_(b), s_(s) {}
    int channels() const override { return b_.channels(); }
    std::size_t nbytes() const override { return b_.nbytes(); }
    std::string describe() const override { return b_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wi, wo); }
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override {
        b_.eval({wi, n}, {wo, n}, {out, n});
    }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override {
        return s_ ? s_->sample(wo, u1, u2) : Brdf::sample_above(wo, u1, u2);
    }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override {
        return s_ ? s_->pdf(wo, wi) : Brdf::pdf_above(wo, wi);
    }

private:
    const Brdf& b_;
    const S* s_;
};

double albedo_variance(const Brdf& b, const Vec3& wo, int n) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double s1 = 0, s2 = 0;
    for (int k = 0; k < n; ++k) {
        const BrdfSample s = b.sample(wo, u(rng), u(rng));
        const double w = (s.weight[0] + s.weight[1] + s.weight[2]) / 3.0;
        s1 += w, s2 += w * w;
    }
    return s2 / n - (s1 / n) * (s1 / n);
}

double sample_rate(const Brdf& b) {
    const Vec3 wo = spherical_direction(0.6, 0.3);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<std::array<double, 2>> us(std::size_t{1} << 20);
    for (auto& x : us) x = {u(rng), u(rng)};
    const std::vector<Vec3> wos(us.size(), wo);
    std::vector<BrdfSample> out(us.size());
    std::vector<double> rates;
    for (int rep = 0; rep < 7; ++rep) {
        const auto t0 = bench::Clock::now();
        b.sample(wos, us, out);
        rates.push_back(us.size() / (bench::ms_between(t0, bench::Clock::now()) * 1e3));
    }
    return bench::median(rates);
}

// Draws alone (the sampler's sample(), no weight), one at a time, M/s, median of 7.
template <typename S>
double draw_rate(const S& sampler) {
    const Vec3 wo = spherical_direction(0.6, 0.3);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<std::array<double, 2>> us(std::size_t{1} << 20);
    for (auto& x : us) x = {u(rng), u(rng)};
    std::vector<double> rates;
    double checksum = 0.0;
    for (int rep = 0; rep < 7; ++rep) {
        const auto t0 = bench::Clock::now();
        for (const auto& x : us) checksum += sampler.sample(wo, x[0], x[1]).pdf;
        rates.push_back(us.size() / (bench::ms_between(t0, bench::Clock::now()) * 1e3));
    }
    return checksum > 0.0 ? bench::median(rates) : 0.0;
}

template <typename Make>
double build_ms(int reps, Make make) {
    std::vector<double> ms;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = bench::Clock::now();
        const auto s = make();
        ms.push_back(bench::ms_between(t0, bench::Clock::now()));
    }
    return bench::median(ms);
}

}  // namespace

int main(int argc, char** argv) try {
    const bench::SweepArgs args = bench::parse_sweep_args(
        argc, argv, "",
        {"nmf:rank=2,space=linear,colour=shared,iterations=20", "nmf:rank=4,space=linear,iterations=20",
         "svd:rank=2,space=linear,iterations=20", "svd:rank=4,space=log,iterations=20",
         "nmf:rank=2,space=cbrt,colour=shared,iterations=20"});
    std::vector<std::pair<std::string, Table>> tables;
    for (const auto& path : args.files) tables.emplace_back(path.stem().string(), merl::read(path.string()).table);
    if (tables.empty()) tables.emplace_back("synthetic 90x90x180", bench::synthetic_table(GridSpec{}));
    const int n = 1000000;
    for (const auto& [name, table] : tables) {
        const TabularBrdf source(Table(table), Lookup::Linear);
        for (const std::string& spec : args.specs) {
            const Compressed c = compress(source, spec);
            const auto& f = dynamic_cast<const FactoredBrdf&>(*c.brdf);
            HalfVectorSamplerOptions ho;
            ho.threads = 1;
            FactorSamplerOptions mo;
            mo.density = FactorDensity::Mixture;
            const double factor_ms = build_ms(5, [&] { return FactorSampler(f.factors()); });
            const double mixture_ms = build_ms(5, [&] { return FactorSampler(f.factors(), mo); });
            const double half_ms = build_ms(3, [&] { return HalfVectorSampler(f, ho); });
            const FactorSampler fs(f.factors()), ms(f.factors(), mo);
            const HalfVectorSampler hs(f, ho);
            const SampledWith<FactorSampler> by_factors(f, &fs), by_mixture(f, &ms), cosine(f, nullptr);
            const SampledWith<HalfVectorSampler> by_half(f, &hs);
            std::printf("%s  %s\n", name.c_str(), spec.c_str());
            std::printf("  build (1 thread): factor (marginal) %.2f ms, factor (mixture) %.2f ms, half-vector %.1f ms "
                        "(%.0fx marginal)\n",
                        factor_ms, mixture_ms, half_ms, half_ms / factor_ms);
            std::printf("  theta_o | albedo variance: cosine  half-vector  marginal   mixture | marginal/half "
                        "mixture/half cosine/marginal\n");
            for (double deg : {0.0, 30.0, 60.0, 80.0}) {
                const Vec3 wo = spherical_direction(deg * M_PI / 180.0, 0.3);
                const double vc = albedo_variance(cosine, wo, n), vh = albedo_variance(by_half, wo, n),
                             vf = albedo_variance(by_factors, wo, n), vm = albedo_variance(by_mixture, wo, n);
                std::printf("  %5.0f   | %22.4g %12.4g %9.4g %9.4g | %12.2fx %11.2fx %14.1fx\n", deg, vc, vh, vf, vm,
                            vf / vh, vm / vh, vc / vf);
            }
            const double rf = sample_rate(by_factors), rh = sample_rate(by_half);
            const double df = draw_rate(fs), dh = draw_rate(hs);
            std::printf("  sample() with weight: factor %.2f M/s, half-vector %.2f M/s (%.2fx); draw alone: factor "
                        "%.2f M/s, half-vector %.2f M/s (%.2fx)\n\n",
                        rf, rh, rf / rh, df, dh, df / dh);
            std::fflush(stdout);
        }
    }
} catch (const std::exception& e) {
    std::fprintf(stderr, "factor_sample: %s\n", e.what());
    return 1;
}
