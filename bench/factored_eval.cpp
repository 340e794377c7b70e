// Batch evaluation throughput of factored representations on one core, against the tabular linear
// lookup of the same table measured in the same run, and the time to build each factorisation.
//
// Usage: factored_eval [FILE.binary] [--reps N]
// Without a file the 90x90x180 table is synthetic (bench/common.h). 2^20 direction pairs uniform over
// the upper hemisphere; every repetition times Brdf::eval over the batch for each case, interleaved,
// so the figures read as ratios on a noisy shared machine; this thread's CPU time is reported beside
// the wall time. Build times are compress()'s wall time on one thread. Target (#4): ≥ 20 M pairs/s.
#include <time.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace {

struct Case {
    std::string name;
    std::unique_ptr<brdfz::Brdf> brdf;
    const brdfz::Brdf* use;
    double build_s = 0;
    std::vector<double> ms, cpu_ms;  // wall time, and this thread's CPU time
};

// CPU time of this thread: on a loaded machine it excludes the time slices other processes took.
double thread_cpu_ms() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 9);
    brdfz::Table table = args.path.empty() ? bench::synthetic_table(brdfz::GridSpec{}) : brdfz::merl::read(args.path).table;
    const brdfz::TabularBrdf tabular(std::move(table), brdfz::Lookup::Linear);

    std::vector<Case> cases;
    cases.push_back({"tabular linear (baseline)", nullptr, &tabular, 0, {}, {}});
    const char* specs[] = {
        "svd:rank=4,space=log",                                        // the example, full grid
        "svd:rank=4,space=log,layout=hd_p",
        "nmf:rank=3",                                                  // the example
        "svd:rank=8,space=cos,layout=h_dp,colour=shared,res=32x16x32",  // ~16 KB settings
        "svd:rank=3,space=cos,layout=hd_p,colour=shared,res=32x32x16",
        "svd:rank=4,space=cbrt,res=32x16x16",
        "svd:rank=6,space=cos,colour=shared,res=90x32x16",
        // float16 factors fitted through the lookup: within 2 % on the four RGL files at 14,944 bytes
        "svd:rank=8,space=cos,colour=shared,res=64x48x18,dwarp=0.9,fit=lsq,symmetry=none,dtype=f16",
    };
    brdfz::CompressOptions co;
    co.threads = 1;
    for (const char* spec : specs) {
        brdfz::Compressed c = brdfz::compress(tabular, spec, co);
        Case k{spec, std::move(c.brdf), nullptr, c.build_seconds, {}, {}};
        k.use = k.brdf.get();
        cases.push_back(std::move(k));
    }

    const bench::Pairs pairs = bench::uniform_pairs();
    const std::vector<brdfz::Vec3>& wi = pairs.wi;
    const std::vector<brdfz::Vec3>& wo = pairs.wo;
    std::vector<brdfz::Rgb> out(bench::kPairs);
    const auto run = [&](const Case& c) {
        c.use->eval(std::span<const brdfz::Vec3>(wi), std::span<const brdfz::Vec3>(wo), std::span<brdfz::Rgb>(out));
    };

    double checksum = 0.0;  // every output is summed (untimed) and printed, so no work can be dropped
    for (Case& c : cases) run(c);  // warm-up
    for (int r = 0; r < args.reps; ++r)
        for (Case& c : cases) {
            const auto t0 = bench::Clock::now();
            const double c0 = thread_cpu_ms();
            run(c);
            c.cpu_ms.push_back(thread_cpu_ms() - c0);
            c.ms.push_back(bench::ms_between(t0, bench::Clock::now()));
            checksum += bench::sum_of(out);
        }

    std::printf("table: %s; pairs: %zu uniform on the upper hemisphere, reps: %d (interleaved), checksum %.10g\n",
                args.path.empty() ? "synthetic" : args.path.c_str(), bench::kPairs, args.reps, checksum);
    const double base_ms = bench::median(cases[0].ms), base_cpu = bench::median(cases[0].cpu_ms);
    std::printf("%-62s %9s %9s %7s | %9s %9s %7s | %9s %8s\n", "case", "wall ms", "M pairs/s", "x base", "CPU ms",
                "M pairs/s", "x base", "bytes", "build s");
    for (const Case& c : cases) {
        const double ms = bench::median(c.ms), cpu = bench::median(c.cpu_ms);
        std::printf("%-62s %9.2f %9.2f %7.2f | %9.2f %9.2f %7.2f | %9zu %8.2f\n", c.name.c_str(), ms, bench::kPairs / ms * 1e-3,
                    base_ms / ms, cpu, bench::kPairs / cpu * 1e-3, base_cpu / cpu, c.use->nbytes(), c.build_s);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "factored_eval: %s\n", e.what());
    return 1;
}
