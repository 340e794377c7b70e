// .brdfz open speed: brdfz::container::read of a 90x90x180 float32 table against reading the same
// table's raw bytes.
//
// Usage: container_open [FILE.binary] [--reps N]
// The table (the MERL file given, or a synthetic one) is written to a temporary directory (removed on
// exit) twice: as a .brdfz container and as its raw float32 bytes (17,496,000 bytes). All
// measurements run interleaved in one process on a warm page cache:
//   (a) raw: open, allocate a float array of the table's size (not zeroed), fread into it, close —
//       the cheapest way a program gets the table into memory from a file (the target's baseline);
//   (b) brdfz::container::read: header and structure checksums, HDF5 open and metadata, one read of
//       the dataset into a new Table, its CRC-32C, the TabularBrdf;
//   (c) raw into a preallocated, already touched, page-aligned buffer: the I/O floor, with no
//       allocation (see merl_load.cpp for why page-aligned).
#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/merl.h"
#include "common.h"

namespace {

namespace fs = std::filesystem;

std::FILE* open_or_throw(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw brdfz::IoError(path, "cannot open");
    return f;
}

struct Measurement {
    const char* name;
    std::function<void()> run;
    std::vector<double> ms, cpu_ms;  // wall time, and this thread's CPU time (user + system)
};

double thread_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 25);
    // Large blocks from the heap, never returned to the system: otherwise (a) and (b) pay page faults
    // for their fresh 17.5 MB allocation in some repetitions and not in others (glibc's adaptive mmap
    // threshold), which dominates the spread of both; with this, both measure reading and verifying.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest allowed value on 64-bit hosts
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    const brdfz::Table table = args.path.empty() ? bench::synthetic_table(brdfz::GridSpec{}) : brdfz::merl::read(args.path).table;
    const std::size_t bytes = table.bins() * 3 * sizeof(float);

    bench::TempDir tmp;
    const std::string container = (tmp.path() / "table.brdfz").string(), raw = (tmp.path() / "table.f32").string();
    brdfz::container::write(container, brdfz::TabularBrdf(table));
    {
        std::FILE* f = std::fopen(raw.c_str(), "wb");
        if (!f || std::fwrite(table.data(), 1, bytes, f) != bytes || std::fclose(f) != 0)
            throw brdfz::IoError(raw, "cannot write");
    }

    constexpr std::size_t kPage = 4096;
    struct Free {
        void operator()(void* p) const { std::free(p); }
    };
    std::unique_ptr<unsigned char, Free> floor(static_cast<unsigned char*>(std::aligned_alloc(kPage, (bytes + kPage - 1) / kPage * kPage)));
    if (!floor) throw std::bad_alloc();
    std::memset(floor.get(), 1, bytes);

    double checksum = 0.0;  // consumes every result so none is optimised away
    Measurement ms[] = {
        {"(a) raw: allocate + fread", [&] {
             std::FILE* f = open_or_throw(raw);
             const std::unique_ptr<float[]> v(new float[bytes / sizeof(float)]);  // not zeroed: fread fills it
             const std::size_t got = std::fread(v.get(), 1, bytes, f);
             std::fclose(f);
             checksum += static_cast<double>(got) + v[bytes / sizeof(float) / 2];
         }, {}, {}},
        {"(b) container::read", [&] {
             const brdfz::container::ReadResult r = brdfz::container::read(container);
             checksum += static_cast<double>(r.brdf->nbytes());
         }, {}, {}},
        {"(c) raw: fread, no allocation", [&] {
             std::FILE* f = open_or_throw(raw);
             const std::size_t got = std::fread(floor.get(), 1, bytes, f);
             std::fclose(f);
             checksum += static_cast<double>(got) + floor.get()[bytes / 2];
         }, {}, {}},
    };

    // Warm the page cache (and the allocator) with one untimed run of each; check the round trip.
    for (Measurement& m : ms) m.run();
    const brdfz::container::ReadResult check = brdfz::container::read(container);
    if (!(dynamic_cast<const brdfz::TabularBrdf&>(*check.brdf).table() == table))
        throw brdfz::Error("container round trip changed the table");
    std::printf("table: %s %s, %zu bytes of values; container file %ju bytes\n",
                args.path.empty() ? "synthetic" : args.path.c_str(), table.grid().str().c_str(), bytes,
                static_cast<std::uintmax_t>(fs::file_size(container)));

    // Successive repetitions step through every order of the three, so none always follows another.
    int order[] = {0, 1, 2};
    for (int r = 0; r < args.reps; ++r, std::next_permutation(std::begin(order), std::end(order))) {
        for (int k : order) {
            const double c0 = thread_cpu_ms();
            const auto t0 = bench::Clock::now();
            ms[k].run();
            ms[k].ms.push_back(bench::ms_between(t0, bench::Clock::now()));
            ms[k].cpu_ms.push_back(thread_cpu_ms() - c0);
        }
    }

    // Wall-time medians, and CPU-time medians: on a loaded machine a reader that makes more system
    // calls is more often preempted for another process's time slice (4 ms here), which wall time
    // counts and CPU time does not.
    std::printf("reps: %d (interleaved), checksum %.6g\n", args.reps, checksum);
    for (const Measurement& m : ms) {
        const double t = bench::median(m.ms);
        std::printf("%-31s median %8.3f ms  (%.2f GB/s)  CPU time median %8.3f ms\n", m.name, t, bytes / t * 1e-6,
                    bench::median(m.cpu_ms));
    }
    const double a = bench::median(ms[0].ms), b = bench::median(ms[1].ms), c = bench::median(ms[2].ms);
    const double a_cpu = bench::median(ms[0].cpu_ms), b_cpu = bench::median(ms[1].cpu_ms);
    std::printf("ratio b/a: wall %.2f, CPU %.2f (target <= 1.5: %s); b/c wall %.2f\n", b / a, b_cpu / a_cpu,
                b / a <= 1.5 ? "met" : b_cpu / a_cpu <= 1.5 ? "met in CPU time only" : "NOT met", b / c);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "container_open: %s\n", e.what());
    return 1;
}
