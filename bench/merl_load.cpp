// MERL load speed: brdfz::merl::read against the floor of reading the same bytes with fread.
//
// Usage: merl_load [FILE.binary] [--reps N]
// Without a file, a synthetic 90x90x180 table is written with brdfz::merl::write to a temporary
// directory (removed on exit) and read back. All measurements run interleaved in one process on a
// warm page cache, so their ratios stay meaningful when absolute times drift on a shared machine:
//   (a) fread of the whole file into one preallocated buffer (open + fread + close) — the baseline;
//   (b) brdfz::merl::read;
//   (c) fread of the same bytes through one reused buffer of the reader's chunk size — the I/O floor
//       of a streaming reader, which writes no 35 MB destination.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/merl.h"
#include "common.h"

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kChunkBytes = std::size_t{1} << 19;  // brdfz::merl::read's chunk (65536 doubles)
constexpr std::size_t kPage = 4096;

// A page-aligned buffer, touched once so no timed run pays its page faults. Page-aligned because the
// kernel copies from page-aligned page-cache pages, and on this machine's CPU that copy runs ~5x
// slower when the destination sits 8 or 16 bytes past a page boundary — exactly where malloc puts
// large blocks — which would turn the floor into no floor (see README.md).
class PageBuffer {
public:
    explicit PageBuffer(std::size_t size)
        : size_(size), data_(static_cast<unsigned char*>(std::aligned_alloc(kPage, (size + kPage - 1) / kPage * kPage))) {
        if (!data_) throw std::bad_alloc();
        std::memset(data_.get(), 1, size_);
    }
    unsigned char* data() const { return data_.get(); }
    std::size_t size() const { return size_; }

private:
    struct Free {
        void operator()(unsigned char* p) const { std::free(p); }
    };
    std::size_t size_;
    std::unique_ptr<unsigned char, Free> data_;
};

// Reads the whole file through `buffer`, one fread call per buffer-full; returns the last byte read.
unsigned char fread_through(const std::string& path, const PageBuffer& buffer) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw brdfz::IoError(path, "cannot open");
    unsigned char last = 0;
    std::size_t got;
    while ((got = std::fread(buffer.data(), 1, buffer.size(), f)) > 0) last = buffer.data()[got - 1];
    std::fclose(f);
    return last;
}

struct Measurement {
    const char* name;
    std::function<void()> run;
    std::vector<double> ms;
};

}  // namespace

int main(int argc, char** argv) try {
    const bench::Args args = bench::parse_args(argc, argv, 15);

    std::string path = args.path;
    std::unique_ptr<bench::TempDir> tmp;
    if (path.empty()) {
        tmp = std::make_unique<bench::TempDir>();
        path = (tmp->path() / "synthetic.binary").string();
        brdfz::merl::write(path, bench::synthetic_table(brdfz::GridSpec{}));
    }

    const PageBuffer whole(fs::file_size(path)), chunk(kChunkBytes);
    double checksum = 0.0;  // consumes every result so none is optimised away
    Measurement ms[] = {
        {"(a) fread whole file", [&] { checksum += fread_through(path, whole); }, {}},
        {"(b) brdfz::merl::read", [&] {
             const brdfz::merl::ReadResult res = brdfz::merl::read(path);
             checksum += static_cast<double>(res.counts.valid) + res.table.at(res.table.bins() / 2, 0);
         }, {}},
        {"(c) fread 512 KiB chunks", [&] { checksum += fread_through(path, chunk); }, {}},
    };

    // Warm the page cache (and the allocator) with one untimed run of each.
    for (Measurement& m : ms) m.run();
    const brdfz::merl::ReadResult info = brdfz::merl::read(path);
    std::printf("file: %s (%zu bytes), %s table, %zu valid / %zu bins\n", args.path.empty() ? "synthetic" : path.c_str(),
                whole.size(), info.table.grid().str().c_str(), info.counts.valid, info.table.bins());

    // Each measurement leaves a different footprint in a last-level cache about the file's size, so
    // successive repetitions step through every order of the three: none always follows the same one.
    int order[] = {0, 1, 2};
    for (int r = 0; r < args.reps; ++r, std::next_permutation(std::begin(order), std::end(order))) {
        for (int k : order) {
            const auto t0 = bench::Clock::now();
            ms[k].run();
            ms[k].ms.push_back(bench::ms_between(t0, bench::Clock::now()));
        }
    }

    std::printf("reps: %d (interleaved), checksum %.6g\n", args.reps, checksum);
    for (const Measurement& m : ms) {
        const double t = bench::median(m.ms);
        std::printf("%-25s median %8.3f ms  (%.2f GB/s of file)\n", m.name, t, whole.size() / t * 1e-6);
    }
    const double a = bench::median(ms[0].ms), b = bench::median(ms[1].ms), c = bench::median(ms[2].ms);
    std::printf("ratio b/a: %.2f (target <= 2: %s); b/c: %.2f\n", b / a, b / a <= 2.0 ? "met" : "NOT met", b / c);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "merl_load: %s\n", e.what());
    return 1;
}
