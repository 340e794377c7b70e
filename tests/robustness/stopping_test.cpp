// Long operations stop when their caller's stop check throws (brdfz/control.h: Python's Ctrl-C and
// raising progress callables go through it), at once and leaving no output; `threads` is bounded by a
// documented limit before any work.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
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
using Clock = std::chrono::steady_clock;

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

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Seconds `fn` takes when it is stopped at the check's `after`-th call (it must be stopped).
template <typename Fn>
double stopped_after(int after, Fn fn) {
    Trip trip(after);
    const StopScope scope(trip.check());
    const auto t0 = Clock::now();
    CHECK_THROWS_AS(fn(), Stop);
    return seconds_since(t0);
}

}  // namespace

TEST_CASE("robustness: a stop check ends tabulation, metrics, factorisation, a fit and a selection at once",
          "[robustness][stop]") {
    TabulateOptions tab;
    tab.grid = GridSpec{45, 45, 90};
    tab.threads = 2;
    const Table table = tabulate(material(), tab).table;
    const TabularBrdf stored(table, Lookup::Linear);

    const auto t0 = Clock::now();
    MetricOptions over;
    over.over = Over::Directions;
    over.directions = std::size_t{1} << 20;
    over.threads = 2;
    compare(material(), stored, over);
    const double whole = seconds_since(t0);
    // Stopped at the third check, the same metrics take a small part of the whole.
    CHECK(stopped_after(3, [&] { compare(material(), stored, over); }) < 0.25 * whole);

    stopped_after(3, [&] { tabulate(material(), tab); });
    CompressOptions co;
    co.threads = 2;
    stopped_after(5, [&] { compress(stored, "nmf:rank=4,iterations=100000,res=45x45x90", co); });
    FitOptions fo;
    fo.threads = 2;
    stopped_after(3, [&] { fit(stored, "lambert+ggx", fo); });
    SelectOptions so;
    so.max_error = 1e-12;
    so.candidates = {"tabular:res=8x8x16", "tabular:res=16x16x32"};
    stopped_after(1, [&] { select_representation(stored, so); });
}

TEST_CASE("robustness: a stopped save writes nothing; a check that never throws changes nothing",
          "[robustness][stop]") {
    const test::TempDir dir;
    SaveOptions o;
    o.grid = GridSpec{45, 45, 90};
    // A material no format stores as it is: every one tabulates it.
    const CoatedDiffuse coated;
    for (const char* name : {"x.binary", "x.brdfz", "x.exr", "x.npy"}) {
        const fs::path p = dir.path / name;
        stopped_after(2, [&] { save(coated, p.string(), o); });
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
