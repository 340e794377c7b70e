// Batch evaluation throughput of compact tables (float16, u8log; 3-D and bivariate) against the
// float32 TabularBrdf baseline on the same grid, measured in the same run, on one core.
//
// Usage: compact_eval [FILE.binary] [--reps N]
// Without a file the table is synthetic (bench/common.h). 2^20 direction pairs uniform over the upper
// hemisphere are generated once; each repetition times Brdf::eval over the whole batch for every case,
// interleaved, so results read as ratios to the float32 table of the same grid on a noisy machine.
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "brdfz/formats/merl.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "common.h"

namespace {

struct Case {
    std::string name;
    std::unique_ptr<brdfz::Brdf> brdf;
    std::size_t baseline;  // index of the float32 case on the same grid
    std::vector<double> ms;
};

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 9);
    const brdfz::Table full =
        args.path.empty() ? bench::synthetic_table(brdfz::GridSpec{}) : brdfz::merl::read(args.path).table;
    const brdfz::TabularBrdf source(full);

    // Grids: MERL's own, a coarse 3-D one, and bivariate (θh, θd) tables; each as f32, f16 and u8log.
    std::vector<Case> cases;
    for (const brdfz::GridSpec& g : {brdfz::GridSpec{90, 90, 180}, brdfz::GridSpec{32, 32, 64}, brdfz::GridSpec{90, 90, 1},
                                     brdfz::GridSpec{64, 32, 1}}) {
        brdfz::TabulateOptions t;
        t.grid = g;
        if (!(g == full.grid())) t.supersample = {2, 2, g.n_phi_d == 1 ? 180 : 2};
        const brdfz::Table table = g == full.grid() ? full : brdfz::tabulate(source, t).table;
        for (brdfz::Lookup lookup : {brdfz::Lookup::Nearest, brdfz::Lookup::Linear}) {
            const std::size_t base = cases.size();
            cases.push_back({"", std::make_unique<brdfz::TabularBrdf>(table, lookup), base, {}});
            for (brdfz::TableDtype d : {brdfz::TableDtype::F16, brdfz::TableDtype::U8Log})
                cases.push_back(
                    {"", std::make_unique<brdfz::CompactTableBrdf>(brdfz::CompactTable::encode(table, d), lookup), base, {}});
        }
    }
    for (Case& c : cases) c.name = c.brdf->describe();

    const bench::Pairs pairs = bench::uniform_pairs();
    const std::vector<brdfz::Vec3>& wi = pairs.wi;
    const std::vector<brdfz::Vec3>& wo = pairs.wo;
    std::vector<brdfz::Rgb> out(bench::kPairs);
    const auto run = [&](const Case& c) {
        c.brdf->eval(std::span<const brdfz::Vec3>(wi), std::span<const brdfz::Vec3>(wo), std::span<brdfz::Rgb>(out));
    };

    double checksum = 0.0;  // every output is summed (untimed) and printed, so no work can be dropped
    for (Case& c : cases) run(c);  // warm-up
    for (int r = 0; r < args.reps; ++r)
        for (Case& c : cases) {
            const auto t0 = bench::Clock::now();
            run(c);
            c.ms.push_back(bench::ms_between(t0, bench::Clock::now()));
            checksum += bench::sum_of(out);
        }

    std::printf("source: %s\n", args.path.empty() ? "synthetic 90x90x180" : args.path.c_str());
    std::printf("pairs: %zu uniform on the upper hemisphere, reps: %d (interleaved), checksum %.10g\n", bench::kPairs,
                args.reps, checksum);
    for (const Case& c : cases) {
        const double ms = bench::median(c.ms);
        std::printf("%-58s %8zu B  median %8.2f ms  %6.2f M pairs/s  %5.2f x float32 time\n", c.name.c_str(),
                    c.brdf->nbytes(), ms, bench::kPairs / ms * 1e-3, ms / bench::median(cases[c.baseline].ms));
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "compact_eval: %s\n", e.what());
    return 1;
}
