// Batch eval, pdf and sample (with weights) of an RGL-EPFL file and of a representation compressed
// from it, on one thread, in C++: the figures bench/vs_mitsuba.py measures through Python, without
// the Python module's per-row normalisation and copies.
//
// Usage: rgl_batch FILE.bsdf [--spec SPEC] [--reps N]
// 2^20 pairs, wi and wo uniform on the upper hemisphere (bench/common.h's seed), u uniform in [0, 1)².
// Each repetition times every case in turn (interleaved); medians of wall and thread CPU time. The
// default spec is the ≤ 16 KB representation of bench/README.md. The batch kernels' SIMD build is
// the widest the CPU has (detail/simd.h), printed first.
#include <time.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/simd.h"
#include "common.h"

namespace {

double thread_cpu_ms() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

struct Case {
    std::string name;
    std::function<double()> run;  // returns a checksum of its outputs
    std::vector<double> ms, cpu_ms;
};

}  // namespace

int main(int argc, char** argv) try {
    std::string path, spec = "svd:rank=8,space=cos,colour=shared,res=64x48x18,dwarp=0.9,fit=lsq,symmetry=none,dtype=f16";
    int reps = 7;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--spec" && i + 1 < argc) {
            spec = argv[++i];
        } else if (a == "--reps" && i + 1 < argc) {
            reps = std::atoi(argv[++i]);
        } else if (!a.empty() && a[0] != '-' && path.empty()) {
            path = a;
        } else {
            path.clear();
            break;
        }
    }
    if (path.empty() || reps < 1) {
        std::fprintf(stderr, "usage: %s FILE.bsdf [--spec SPEC] [--reps N]\n", argv[0]);
        return 2;
    }
    const brdfz::rgl::ReadResult rgl = brdfz::rgl::read(path);
    brdfz::CompressOptions co;
    co.threads = 1;
    const brdfz::Compressed repr = brdfz::compress(*rgl.brdf, spec, co);

    const bench::Pairs pairs = bench::uniform_pairs();
    const std::size_t n = bench::kPairs;
    std::vector<std::array<double, 2>> u(n);
    std::mt19937_64 rng(20261201);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (auto& x : u) x = {u01(rng), u01(rng)};
    std::vector<brdfz::Rgb> f(n);
    std::vector<double> p(n);
    std::vector<brdfz::BrdfSample> s(n);
    const std::span<const brdfz::Vec3> wi(pairs.wi), wo(pairs.wo);

    std::vector<Case> cases;
    for (const auto& [label, brdf] : {std::pair<std::string, const brdfz::Brdf*>{"rgl", rgl.brdf.get()},
                                      std::pair<std::string, const brdfz::Brdf*>{"repr", repr.brdf.get()}}) {
        const brdfz::Brdf* b = brdf;
        cases.push_back({label + " eval", [&, b] {
                             b->eval(wi, wo, f);
                             return bench::sum_of(f);
                         }, {}, {}});
        cases.push_back({label + " pdf", [&, b] {
                             b->pdf(wo, wi, p);
                             double t = 0;
                             for (double x : p) t += x;
                             return t;
                         }, {}, {}});
        cases.push_back({label + " sample", [&, b] {
                             b->sample(wo, u, s);
                             double t = 0;
                             for (const brdfz::BrdfSample& x : s) t += x.pdf + x.weight[0];
                             return t;
                         }, {}, {}});
    }
    double checksum = 0;
    for (Case& c : cases) checksum += c.run();  // warm-up, and the samplers built
    for (int r = 0; r < reps; ++r)
        for (Case& c : cases) {
            const auto t0 = bench::Clock::now();
            const double c0 = thread_cpu_ms();
            checksum += c.run();
            c.cpu_ms.push_back(thread_cpu_ms() - c0);
            c.ms.push_back(bench::ms_between(t0, bench::Clock::now()));
        }
    std::printf("file: %s\nrepr: %s (%zu B): %s\nSIMD: %s; pairs: %zu; reps: %d; checksum %.10g\n", path.c_str(),
                spec.c_str(), repr.brdf->nbytes(), repr.brdf->describe().c_str(),
                brdfz::simd_name(), n, reps, checksum);
    std::printf("%-14s %9s %9s | %9s %9s\n", "case", "wall ms", "M/s", "CPU ms", "M/s");
    for (const Case& c : cases) {
        const double ms = bench::median(c.ms), cpu = bench::median(c.cpu_ms);
        std::printf("%-14s %9.2f %9.2f | %9.2f %9.2f\n", c.name.c_str(), ms, n / ms * 1e-3, cpu, n / cpu * 1e-3);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "rgl_batch: %s\n", e.what());
    return 1;
}
