// Long operations stop when their caller's stop check throws (brdfz/control.h: Python's Ctrl-C and
// raising progress callables go through it), at once and leaving no output; `threads` is bounded by a
// documented limit before any work.
#include <catch2/catch.hpp>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <string>

#include "brdfz/compress.h"
#include "brdfz/control.h"
#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/select.h"
#include "brdfz/tabulate.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

const AnalyticBrdf& material() {
    static const AnalyticBrdf m("lambert+ggx", {0.3, 0.4, 0.5, 0.2, 0.2, 0.2, 0.3, 0.04});
    return m;
}

// What the check throws: not a brdfz::Error, as the control.h contract asks.
struct Stop {};

// A check that throws from its `after`-th call on (from any thread), counting the calls.
struct Trip {
    explicit Trip(int after) : after(after) {}
    StopCheck check() {
        return [this] {
            if (++calls >= after) throw Stop{};
        };
    }
    const int after;
    std::atomic<int> calls{0};
};

// Runs `fn` under a check that throws at its `after`-th call: `fn` must end with that exception, having
// called the check at most once more on each of its `threads` threads (each finishes the item it is on).
template <typename Fn>
void stopped_after(int after, int threads, Fn fn) {
    Trip trip(after);
    const StopScope scope(trip.check());
    CHECK_THROWS_AS(fn(), Stop);
    CHECK(trip.calls >= after);
    CHECK(trip.calls <= after + threads - 1);
}

}  // namespace

TEST_CASE("robustness: a stop check ends tabulation, metrics, factorisation, a fit and a selection at once",
          "[robustness][stop]") {
    TabulateOptions tab;
    tab.grid = GridSpec{32, 32, 64};
    tab.threads = 2;
    const TabularBrdf stored(tabulate(material(), tab).table, Lookup::Linear);

    MetricOptions over;
    over.over = Over::Directions;
    over.directions = std::size_t{1} << 24;  // 4096 blocks of pairs, of which a few are drawn
    over.threads = 2;
    stopped_after(3, 2, [&] { compare(material(), stored, over); });
    stopped_after(3, 2, [&] { tabulate(material(), tab); });
    CompressOptions co;
    co.threads = 2;
    stopped_after(5, 2, [&] { compress(stored, "nmf:rank=4,iterations=100000,res=32x16x32", co); });
    FitOptions fo;
    fo.threads = 2;
    stopped_after(3, 2, [&] { fit(stored, "lambert+ggx", fo); });
    SelectOptions so;
    so.max_error = 1e-12;
    so.candidates = {"tabular:res=8x8x16", "tabular:res=16x16x32"};
    so.trial.compress.threads = so.trial.metrics.threads = 1;
    stopped_after(2, 1, [&] { select_representation(stored, so); });
}

TEST_CASE("robustness: a stopped save writes nothing, a check that never throws changes nothing",
          "[robustness][stop]") {
    const test::TempDir dir;
    SaveOptions o;
    o.grid = GridSpec{45, 45, 90};
    o.threads = 1;
    // A material no format stores as it is: every one tabulates it.
    const CoatedDiffuse coated;
    for (const char* name : {"x.binary", "x.brdfz", "x.exr", "x.npy"}) {
        const fs::path p = dir.path / name;
        stopped_after(2, 1, [&] { save(coated, p.string(), o); });
        CHECK(fs::is_empty(dir.path));
    }
    TabulateOptions tab;
    tab.grid = GridSpec{16, 16, 32};
    const Table free = tabulate(material(), tab).table;
    Trip never(1 << 30);
    const StopScope scope(never.check());
    const Table checked = tabulate(material(), tab).table;
    CHECK(never.calls > 0);
    CHECK(std::memcmp(free.data(), checked.data(), 3 * free.bins() * sizeof(float)) == 0);  // NaNs included
}

TEST_CASE("robustness: threads above kMaxThreads are a ValueError naming the limit, before any work",
          "[robustness][limits]") {
    const std::string message = "threads = 1000000000 is above the limit of 1024 (0: one per hardware thread)";
    CHECK_THROWS_WITH(resolve_threads(1000000000), message);
    CHECK(resolve_threads(kMaxThreads) == kMaxThreads);
    CHECK(resolve_threads(0) >= 1);
    CompressOptions co;
    co.threads = 1000000000;
    CHECK_THROWS_WITH(compress(material(), "tabular:res=8x8x16", co), message);
    MetricOptions mo;
    mo.threads = 1000000000;
    mo.over = Over::Directions;
    mo.directions = 1024;
    CHECK_THROWS_WITH(compare(material(), material(), mo), message);
    FitOptions fo;
    fo.threads = 1000000000;
    TabulateOptions tab;
    tab.grid = GridSpec{8, 8, 16};
    CHECK_THROWS_WITH(fit(TabularBrdf(tabulate(material(), tab).table, Lookup::Linear), "lambert", fo), message);
}
