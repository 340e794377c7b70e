// Speed of analytic models (issue 3 targets):
//   fitting lambert+ggx to a 90x90x180 MERL table with default options: <= 2 s wall (2 cores);
//   batch evaluation of lambert+ggx on one core: >= 50 M pairs/s.
//
// Usage: fit [FILE.binary] [--reps N]
// Without a file the table is synthetic (bench::synthetic_table). Evaluation: 2^20 direction pairs
// uniform over the upper hemisphere, each repetition timing, over the same arrays,
//   stream      one pass reading wi, wo and writing out (the memory-traffic floor);
//   per-pair    Brdf::eval one pair at a time (what a caller gets without the batch kernel);
//   batch       Brdf::eval over the whole batch.
// Fitting: each repetition times brdfz::fit with default options, beside two baselines measured in
// the same run: reading the MERL file (what precedes any fit of a file) and brdfz::compare of the
// fitted model against the table (one evaluation over all 1.4 M bins, as the fit's report does).
#include <cstdio>
#include <functional>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "brdfz/fit/fit.h"
#include "brdfz/formats/merl.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace {

struct Case {
    const char* name;
    std::function<void()> run;
    std::vector<double> ms;
};

void time_cases(std::span<Case> cases, int reps, const std::function<void()>& after) {
    for (Case& c : cases) c.run();  // warm-up
    for (int r = 0; r < reps; ++r)
        for (Case& c : cases) {
            const auto t0 = bench::Clock::now();
            c.run();
            c.ms.push_back(bench::ms_between(t0, bench::Clock::now()));
            after();
        }
}

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 7);

    // Evaluation, one core.
    const brdfz::AnalyticBrdf model("lambert+ggx", {0.2, 0.3, 0.4, 0.8, 0.7, 0.6, 0.15, 0.05});
    const bench::Pairs pairs = bench::uniform_pairs();
    const std::vector<brdfz::Vec3>& wi = pairs.wi;
    const std::vector<brdfz::Vec3>& wo = pairs.wo;
    std::vector<brdfz::Rgb> out(bench::kPairs);
    double checksum = 0.0;  // outputs are summed (untimed) and printed, so no work can be dropped
    Case eval_cases[] = {
        {"stream baseline", [&] {
             for (std::size_t k = 0; k < bench::kPairs; ++k)
                 out[k] = {wi[k].x + wo[k].x, wi[k].y + wo[k].y, wi[k].z + wo[k].z};
         }, {}},
        {"per-pair eval", [&] {
             for (std::size_t k = 0; k < bench::kPairs; ++k) out[k] = model.eval(wi[k], wo[k]);
         }, {}},
        {"batch eval", [&] {
             model.eval(std::span<const brdfz::Vec3>(wi), std::span<const brdfz::Vec3>(wo), std::span<brdfz::Rgb>(out));
         }, {}},
    };
    time_cases(eval_cases, args.reps, [&] {
        checksum += bench::sum_of(out);
    });
    std::printf("evaluation of %s\n", model.describe().c_str());
    std::printf("pairs: %zu uniform on the upper hemisphere, reps: %d (interleaved), checksum %.10g\n", bench::kPairs,
                args.reps, checksum);
    for (const Case& c : eval_cases) {
        const double ms = bench::median(c.ms);
        std::printf("  %-16s median %8.2f ms  %7.2f M pairs/s\n", c.name, ms, bench::kPairs / ms * 1e-3);
    }
    const double rate = bench::kPairs / bench::median(eval_cases[2].ms) * 1e-3;
    std::printf("target batch eval >= 50 M pairs/s on one core: %s\n\n", rate >= 50 ? "met" : "NOT met");

    // Fitting, default options (all cores).
    brdfz::Table table = args.path.empty() ? bench::synthetic_table(brdfz::GridSpec{}) : brdfz::merl::read(args.path).table;
    const brdfz::TabularBrdf brdf(std::move(table));
    brdfz::FitResult last = brdfz::fit(brdf, "lambert+ggx");
    Case fit_cases[] = {
        {"read baseline", [&] {
             if (!args.path.empty()) checksum += brdfz::merl::read(args.path).table.at(0, 0);
         }, {}},
        {"compare baseline", [&] { checksum += brdfz::compare(brdf, last.model).cos_rmse.mean; }, {}},
        {"fit", [&] { last = brdfz::fit(brdf, "lambert+ggx"); }, {}},
    };
    time_cases(fit_cases, args.reps, [] {});
    std::printf("fit lambert+ggx to %s (90x90x180), default options, reps: %d\n",
                args.path.empty() ? "a synthetic table" : args.path.c_str(), args.reps);
    std::printf("  status %s, %zu samples, %d iterations (%d over all starts), unexplained %.3f\n",
                brdfz::fit_status_name(last.report.status), last.report.samples, last.report.iterations,
                last.report.total_iterations, last.report.unexplained);
    std::printf("  %s\n", last.model.describe().c_str());
    for (const Case& c : fit_cases) {
        if (c.name == std::string("read baseline") && args.path.empty()) continue;
        std::printf("  %-16s median %8.1f ms\n", c.name, bench::median(c.ms));
    }
    const double fit_ms = bench::median(fit_cases[2].ms);
    std::printf("target fit <= 2 s wall: %s\n", fit_ms <= 2000.0 ? "met" : "NOT met");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "fit: %s\n", e.what());
    return 1;
}
