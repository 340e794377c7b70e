// The compact sampler against the fine half-vector sampler: E[w²]/E[w]² of the luminance weight at
// θo = 0, 30, 60, 75° (brdfz/albedo.h, sampler_second_moment), per file and representation, with the
// compact sampler's bytes. Options set the compact sampler's shape, for choosing its defaults on one
// part of the data and reporting on the other:
//   sampler_quality [--spec SPEC]... [--slices K] [--rows R] [--cols C] [--uniform B] [--points P]
//                   [--share S] [--draws N] FILES...
// Prints one CSV row per (file, spec (quoted), view): file,spec,theta_o,repr_bytes,compact_bytes,fine_bytes,
// compact,fine,own (own: the representation's own sampler, e.g. an analytic model's lobe mixture).
#include <cstdio>
#include <exception>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/compress.h"
#include "brdfz/formats/io.h"
#include "brdfz/sample/compact.h"
#include "brdfz/sample/halfvector.h"

using namespace brdfz;

namespace {

// A representation sampled by a given sampler: eval is the representation's, sample and pdf the
// sampler's, so sampler_second_moment measures that sampler on that function.
template <typename Sampler>
class SampledWith final : public Brdf {
public:
    SampledWith(const Brdf& brdf, const Sampler& sampler) : brdf_(brdf), sampler_(sampler) {}
    int channels() const override { return brdf_.channels(); }
    std::size_t nbytes() const override { return brdf_.nbytes(); }
    std::string describe() const override { return brdf_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return brdf_.eval(wi, wo); }
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override {
        brdf_.eval(std::span(wi, n), std::span(wo, n), std::span(out, n));
    }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override { return sampler_.sample(wo, u1, u2); }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return sampler_.pdf(wo, wi); }

private:
    const Brdf& brdf_;
    const Sampler& sampler_;
};

[[noreturn]] void usage(const char* argv0) {
    std::fprintf(stderr,
                 "usage: %s [--spec SPEC]... [--slices K] [--rows R] [--cols C] [--uniform B] [--points P] "
                 "[--share S] [--draws N] [--no-fine] FILES...\n",
                 argv0);
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) try {
    std::vector<std::string> specs, files;
    CompactSamplerOptions options;
    std::size_t draws = 1 << 18;
    bool fine = true;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) usage(argv[0]);
            return argv[++i];
        };
        if (a == "--spec") specs.push_back(next());
        else if (a == "--slices") options.slices = std::atoi(next().c_str());
        else if (a == "--rows") options.rows = std::atoi(next().c_str());
        else if (a == "--cols") options.cols = std::atoi(next().c_str());
        else if (a == "--uniform") options.uniform_share = std::atof(next().c_str());
        else if (a == "--points") options.points = std::atoi(next().c_str());
        else if (a == "--share") options.cosine_share = std::atof(next().c_str());
        else if (a == "--draws") draws = std::strtoull(next().c_str(), nullptr, 10);
        else if (a == "--no-fine") fine = false;
        else if (!a.empty() && a[0] != '-') files.push_back(a);
        else usage(argv[0]);
    }
    if (files.empty() || draws < 2) usage(argv[0]);
    if (specs.empty()) specs.push_back("");  // the file itself
    options.threads = 0;
    std::printf("file,spec,theta_o,repr_bytes,compact_bytes,fine_bytes,compact,fine,own\n");
    const CompressOptions compress_options = with_file_access({});
    for (const std::string& file : files) {
        const Loaded source = load(file);
        for (const std::string& spec : specs) {
            std::unique_ptr<Brdf> built;
            if (!spec.empty()) built = compress(*source.brdf, spec, compress_options).brdf;
            const Brdf& b = spec.empty() ? *source.brdf : *built;
            const CompactSampler compact(b, options);
            const SampledWith<CompactSampler> with_compact(b, compact);
            std::unique_ptr<HalfVectorSampler> half;
            if (fine) half = std::make_unique<HalfVectorSampler>(b);
            const std::string name = file.substr(file.find_last_of('/') + 1);
            for (double deg : {0.0, 30.0, 60.0, 75.0}) {
                const double theta = deg * std::numbers::pi / 180.0;
                const double c = sampler_second_moment(with_compact, theta, draws);
                double f = 0.0;
                if (half) f = sampler_second_moment(SampledWith<HalfVectorSampler>(b, *half), theta, draws);
                const double own = sampler_second_moment(b, theta, draws);
                std::printf("%s,\"%s\",%g,%zu,%zu,%zu,%.4f,%.4f,%.4f\n", name.c_str(), spec.c_str(), deg, b.nbytes(),
                            compact.nbytes(), half ? half->nbytes() : 0, c, f, own);
                std::fflush(stdout);
            }
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "sampler_quality: %s\n", e.what());
    return 1;
}
