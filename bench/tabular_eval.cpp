// Batch evaluation throughput of a 90x90x180 TabularBrdf on one core, nearest and linear lookup.
//
// Usage: tabular_eval [FILE.binary] [--reps N]
// Without a file the table is synthetic (smooth and positive). 2^20 direction pairs uniform over the
// upper hemisphere are generated once; each repetition times Brdf::eval over the whole batch for
// each lookup, interleaved with two baselines over the same arrays, so results read as ratios on a
// noisy shared machine:
//   stream — one pass reading wi, wo and writing out (the memory-traffic floor);
//   coords — brdfz::to_half_diff per pair (the coordinate transform alone, no table access);
//   gather — the table reads alone: each pair's nearest bin, computed beforehand, read into out.
// A lookup costs at least max(coords, gather); near coords + gather means the two do not overlap.
#include <cstdint>
#include <cstdio>
#include <functional>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace {

struct Case {
    const char* name;
    std::function<void()> run;
    std::vector<double> ms;
};

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 9);

    brdfz::Table table = args.path.empty() ? bench::synthetic_table(brdfz::GridSpec{}) : brdfz::merl::read(args.path).table;
    brdfz::TabularBrdf brdf(std::move(table));

    const bench::Pairs pairs = bench::uniform_pairs();
    const std::vector<brdfz::Vec3>& wi = pairs.wi;
    const std::vector<brdfz::Vec3>& wo = pairs.wo;
    std::vector<brdfz::Rgb> out(bench::kPairs);

    // The nearest bin of each pair by MERL's arithmetic (table.h's axis maps), for the gather baseline.
    const brdfz::GridSpec& g = brdf.table().grid();
    std::vector<std::uint32_t> bins(bench::kPairs);
    for (std::size_t k = 0; k < bench::kPairs; ++k) {
        const brdfz::HalfDiff hd = brdfz::to_half_diff(wi[k], wo[k]);
        bins[k] = static_cast<std::uint32_t>(g.index(brdfz::axis::bin_of(brdfz::axis::theta_h_to_u(hd.theta_h, g.n_theta_h), g.n_theta_h),
                                                      brdfz::axis::bin_of(brdfz::axis::theta_d_to_u(hd.theta_d, g.n_theta_d), g.n_theta_d),
                                                      brdfz::axis::bin_of(brdfz::axis::phi_d_to_u(hd.phi_d, g.n_phi_d), g.n_phi_d)));
    }
    const float* data = brdf.table().data();

    Case cases[] = {
        {"stream baseline", [&] {
             for (std::size_t k = 0; k < bench::kPairs; ++k)
                 out[k] = {wi[k].x + wo[k].x, wi[k].y + wo[k].y, wi[k].z + wo[k].z};
         }, {}},
        {"coords baseline", [&] {
             for (std::size_t k = 0; k < bench::kPairs; ++k) {
                 const brdfz::HalfDiff hd = brdfz::to_half_diff(wi[k], wo[k]);
                 out[k] = {hd.theta_h, hd.theta_d, hd.phi_d};
             }
         }, {}},
        {"gather baseline", [&] {
             for (std::size_t k = 0; k < bench::kPairs; ++k) {
                 const float* v = data + 3 * static_cast<std::size_t>(bins[k]);
                 out[k] = {v[0], v[1], v[2]};
             }
         }, {}},
        {"eval nearest", [&] {
             brdf.set_lookup(brdfz::Lookup::Nearest);
             brdf.eval(std::span<const brdfz::Vec3>(wi), std::span<const brdfz::Vec3>(wo), std::span<brdfz::Rgb>(out));
         }, {}},
        {"eval linear", [&] {
             brdf.set_lookup(brdfz::Lookup::Linear);
             brdf.eval(std::span<const brdfz::Vec3>(wi), std::span<const brdfz::Vec3>(wo), std::span<brdfz::Rgb>(out));
         }, {}},
    };

    double checksum = 0.0;  // every output is summed (untimed) and printed, so no work can be dropped
    for (Case& c : cases) c.run();  // warm-up: page in the arrays and the table
    for (int r = 0; r < args.reps; ++r) {
        for (Case& c : cases) {
            const auto t0 = bench::Clock::now();
            c.run();
            c.ms.push_back(bench::ms_between(t0, bench::Clock::now()));
            checksum += bench::sum_of(out);
        }
    }

    std::printf("table: %s, %s\n", args.path.empty() ? "synthetic" : args.path.c_str(), brdf.describe().c_str());
    std::printf("pairs: %zu uniform on the upper hemisphere, reps: %d (interleaved), checksum %.10g\n", bench::kPairs,
                args.reps, checksum);
    const double coords_ms = bench::median(cases[1].ms);
    for (const Case& c : cases) {
        const double ms = bench::median(c.ms);
        std::printf("%-16s median %8.2f ms  %7.2f M pairs/s  %5.2f x coords time\n", c.name, ms,
                    bench::kPairs / ms * 1e-3, ms / coords_ms);
    }
    const double nearest = bench::kPairs / bench::median(cases[3].ms) * 1e-3;
    const double linear = bench::kPairs / bench::median(cases[4].ms) * 1e-3;
    std::printf("target nearest >= 20 M pairs/s: %s; linear >= 10 M pairs/s: %s\n", nearest >= 20 ? "met" : "NOT met",
                linear >= 10 ? "met" : "NOT met");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "tabular_eval: %s\n", e.what());
    return 1;
}
