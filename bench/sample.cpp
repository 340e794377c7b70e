// Importance-sampling benchmark (issue 5): speed of the tabular sampler on one core, and variance of
// Monte Carlo estimates at equal sample counts against cosine-weighted sampling and against sampling a
// fitted lambert+ggx proxy.
//   sample [--fine] [MERL files...]   (default: the built-in material tabulated at 90x90x180; --fine: the
//                                      half-vector sampler instead of the compact one)
// Estimators: directional albedo ρ(θo) = E[f·cosθi/pdf], and a pixel lit by a smooth environment
// L(wi) = 1 + 20·max(0, wi·s)^32 (a broad sky with a bright soft patch), E[L·f·cosθi/pdf].
// The figure reported per estimator is the variance of one sample's contribution (mean channel).
// Every sampler's weight uses the data's f: only the density the directions are drawn from differs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <random>
#include <string>
#include <vector>

#include "brdfz/fit/fit.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"

using namespace brdfz;

namespace {

// Cosine-weighted sampling of the same BRDF: the baseline.
class CosineSampled final : public Brdf {
public:
    explicit CosineSampled(const Brdf& b) : b_(b) {}
    int channels() const override { return b_.channels(); }
    std::size_t nbytes() const override { return b_.nbytes(); }
    std::string describe() const override { return "cosine-sampled " + b_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wi, wo); }

private:
    const Brdf& b_;
};

// The data, sampled with a fitted analytic proxy's lobe mixture: weight = f_data·cosθi / pdf_proxy.
class ProxySampled final : public Brdf {
public:
    ProxySampled(const Brdf& b, const AnalyticBrdf& proxy) : b_(b), proxy_(proxy) {}
    int channels() const override { return b_.channels(); }
    std::size_t nbytes() const override { return b_.nbytes(); }
    std::string describe() const override { return "proxy-sampled " + b_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wi, wo); }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override {
        BrdfSample s = proxy_.sample(wo, u1, u2);
        s.weight = {};  // recomputed from eval_above, the data
        return s;
    }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return proxy_.pdf(wo, wi); }

private:
    const Brdf& b_;
    const AnalyticBrdf& proxy_;
};

double environment(const Vec3& wi) {
    const Vec3 s = normalize({-0.4, 0.2, 0.9});
    return 1.0 + 20.0 * std::pow(std::fmax(0.0, dot(wi, s)), 32.0);
}

struct Variances {
    double albedo, env;
    // The env estimate's variance under perfect BRDF sampling (pdf ∝ f·cosθi, weight = ρ): ρ² Var(L),
    // the floor no BRDF sampler goes below, estimated from this sampler's draws by reweighting
    // (E_perfect[g] = E[g·w] / ρ): ρ E[L² w] − E[L w]².
    double env_floor;
};

Variances estimator_variances(const Brdf& b, const Vec3& wo, int n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double s1 = 0, s2 = 0, e1 = 0, e2 = 0, l2w = 0;
    for (int k = 0; k < n; ++k) {
        const BrdfSample s = b.sample(wo, u(rng), u(rng));
        const double w = (s.weight[0] + s.weight[1] + s.weight[2]) / 3.0;
        const double l = s.pdf > 0 ? environment(s.wi) : 0.0;
        s1 += w, s2 += w * w, e1 += w * l, e2 += w * l * w * l, l2w += l * l * w;
    }
    return {s2 / n - (s1 / n) * (s1 / n), e2 / n - (e1 / n) * (e1 / n), (s1 / n) * (l2w / n) - (e1 / n) * (e1 / n)};
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) try {
    std::vector<std::pair<std::string, std::unique_ptr<Brdf>>> materials;
    LoadOptions options;
    for (int i = 1; i < argc; ++i) {
        if (std::string(argv[i]) == "--fine")
            options.sampler = SamplerKind::Fine;
        else
            materials.emplace_back(argv[i], load(argv[i], options).brdf);
    }
    if (materials.empty()) {
        CoatedDiffuseParams p;
        p.alpha = 0.05;
        materials.emplace_back("built-in coated diffuse (alpha 0.05), 90x90x180",
                               std::make_unique<TabularBrdf>(tabulate(CoatedDiffuse(p)).table, Lookup::Linear,
                                                             options.sampler));
    }
    const int n = 1000000;
    for (const auto& [name, brdf] : materials) {
        std::printf("%s\n", name.c_str());
        const FitResult proxy = fit(*brdf, "lambert+ggx");
        std::printf("  proxy: %s (%s, %.2f s)\n", proxy.model.describe().c_str(),
                    fit_status_name(proxy.report.status), proxy.report.seconds);
        const CosineSampled cosine(*brdf);
        const ProxySampled proxied(*brdf, proxy.model);
        std::printf("  variance of one sample (mean channel); ratios cosine/data and data/proxy\n");
        std::printf("  theta_o | albedo: cosine      data     proxy  cos/data data/proxy | env: cosine      data     "
                    "proxy  cos/data data/proxy  cos/floor\n");
        for (double deg : {0.0, 30.0, 60.0, 80.0}) {
            const Vec3 wo = spherical_direction(deg * M_PI / 180.0, 0.3);
            const Variances c = estimator_variances(cosine, wo, n, 1), t = estimator_variances(*brdf, wo, n, 1),
                            p = estimator_variances(proxied, wo, n, 1);
            std::printf("  %5.0f   | %12.4g %9.4g %9.4g %8.1fx %9.2fx | %11.4g %9.4g %9.4g %8.1fx %9.2fx %9.1fx\n", deg,
                        c.albedo, t.albedo, p.albedo, c.albedo / t.albedo, t.albedo / p.albedo, c.env, t.env, p.env,
                        c.env / t.env, t.env / p.env, c.env / t.env_floor);
        }
        // Speed: sample() including the weight (one eval), single thread, after the sampler is built;
        // the same-run baseline is the batch eval at the drawn pairs. Once at a fixed wo, once at
        // random wo (uniform on the hemisphere: every slice, and the table's cache misses).
        brdf->sample(spherical_direction(0.6, 0.3), 0.5, 0.5);
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::vector<std::array<double, 2>> us(1 << 20);
        for (auto& x : us) x = {u(rng), u(rng)};
        std::vector<Vec3> fixed(us.size(), spherical_direction(0.6, 0.3)), random(us.size());
        for (Vec3& w : random) {
            const double z = u(rng), r = std::sqrt(1.0 - z * z), phi = 2.0 * M_PI * u(rng);
            w = {r * std::cos(phi), r * std::sin(phi), z};
        }
        const auto& table = dynamic_cast<const TabularBrdf&>(*brdf);  // every material here is a table
        for (const auto& [label, wos] : {std::pair{"fixed wo (theta 34 deg)", &fixed}, std::pair{"random wo", &random}}) {
            std::vector<double> rates, single_rates, eval_rates, draw_rates, block_rates;
            HalfVectorSampler::Draws block;
            std::vector<Vec3> wis(us.size());
            std::vector<BrdfSample> out(us.size()), drawn(us.size());
            std::vector<Rgb> f(us.size());
            double checksum = 0;
            for (int rep = 0; rep < 7; ++rep) {
                auto t0 = std::chrono::steady_clock::now();
                brdf->sample(*wos, us, out);
                auto t1 = std::chrono::steady_clock::now();
                for (std::size_t k = 0; k < out.size(); ++k) wis[k] = out[k].pdf > 0 ? out[k].wi : Vec3{0, 0, 1};
                auto t2 = std::chrono::steady_clock::now();
                brdf->eval(wis, *wos, f);
                auto t3 = std::chrono::steady_clock::now();
                // The draw alone (direction and pdf, no weight): the table's sampler, one at a time.
                for (std::size_t k = 0; k < us.size(); ++k)
                    drawn[k] = table.sampler().sample((*wos)[k], us[k][0], us[k][1]);
                auto t4 = std::chrono::steady_clock::now();
                // The fine sampler's draws in blocks, as its batch sample() draws (HalfVectorSampler::draw_block).
                if (const HalfVectorSampler* fine = table.sampler().fine())
                    for (std::size_t start = 0; start < us.size(); start += HalfVectorSampler::kBlock) {
                        const std::size_t m = std::min(HalfVectorSampler::kBlock, us.size() - start);
                        fine->draw_block(wos->data() + start, us.data() + start, m, block);
                        checksum += block.pdf[0];
                    }
                auto t5 = std::chrono::steady_clock::now();
                // sample() one call at a time with its weight, as a renderer calls it per path vertex.
                for (std::size_t k = 0; k < us.size(); ++k) out[k] = brdf->sample((*wos)[k], us[k][0], us[k][1]);
                auto t6 = std::chrono::steady_clock::now();
                single_rates.push_back(us.size() / std::chrono::duration<double>(t6 - t5).count() / 1e6);
                rates.push_back(us.size() / std::chrono::duration<double>(t1 - t0).count() / 1e6);
                eval_rates.push_back(us.size() / std::chrono::duration<double>(t3 - t2).count() / 1e6);
                draw_rates.push_back(us.size() / std::chrono::duration<double>(t4 - t3).count() / 1e6);
                if (table.sampler().fine()) block_rates.push_back(us.size() / std::chrono::duration<double>(t5 - t4).count() / 1e6);
                checksum += out[rep].pdf + f[rep][0] + drawn[rep].pdf;
            }
            checksum += out[0].weight[0];
            std::printf("  sample() (%s sampler), %s: %.2f M samples/s (median of 7, one core), %.2f M/s one call at a "
                        "time; eval() alone at the drawn pairs: %.2f M pairs/s; the draw alone: %.2f M/s one at a time",
                        sampler_kind_name(table.sampler().kind()), label, median(rates), median(single_rates),
                        median(eval_rates), median(draw_rates));
            if (!block_rates.empty()) std::printf(", %.2f M/s in blocks", median(block_rates));
            std::printf("  [%g]\n", checksum);
        }
        std::printf("\n");
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "sample: %s\n", e.what());
    return 1;
}
