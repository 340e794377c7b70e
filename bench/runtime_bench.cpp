// A material as a renderer holds it (issue 32's figures), per representation of each file:
//   bytes        the representation's parameters, its sampler's tables, its .brdfz and .brdfzrt files
//   load         container::read of the .brdfz until it can sample, and runtime::Material::open of the
//                .brdfzrt (medians of --reps)
//   first        the first sample() after loading: its time, its allocations, the threads it started
//   memory       heap bytes (mallinfo2) held by the loaded material after it has sampled
//   ns/call      one call at a time and in batches of 2^16, the library's (double) against the runtime's
//                (float32): each comparison's two loops adjacent, in alternating order rep by rep, each
//                timed after an untimed run; the median of the ratios library/runtime (> 1: the runtime
//                is faster), for eval, pdf and sample; the *_f64 columns give the runtime's
//                double calls the library's unit double directions, which the float calls normalise first;
//                the *_same columns give the library the float directions (widened, as a renderer working in
//                float passes them; it normalises them too) against the runtime's float calls
//   runtime_bench [--reps N] [--spec SPEC]... FILES...
// Prints one CSV row per (file, spec).
#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/runtime_layout.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/runtime/runtime.h"
#include "common.h"

using namespace brdfz;
namespace rt = brdfz::runtime;

namespace {
std::atomic<std::size_t> allocations{0};
}
void* operator new(std::size_t n) {
    allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

std::size_t heap_bytes() {
    const struct mallinfo2 m = mallinfo2();
    return m.uordblks + m.hblkhd;
}

int thread_count() {
    int n = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/task")) ++n;
    return n;
}

// Bytes of the tables the representation samples from (an analytic model's lobe mixture: none).
std::size_t sampler_bytes(const Brdf& b) {
    if (const auto* t = dynamic_cast<const LookupTableBrdf*>(&b)) return t->sampler().nbytes();
    if (const auto* f = dynamic_cast<const FactoredBrdf*>(&b)) return f->sampler().nbytes();
    if (const auto* p = dynamic_cast<const PcaBrdf*>(&b)) return p->table().sampler().nbytes();
    if (const auto* h = dynamic_cast<const PhiHBrdf*>(&b)) return h->sampler().nbytes();
    if (const auto* a = dynamic_cast<const AnalyticBrdf*>(&b)) return a->compact_sampler() ? a->compact_sampler()->nbytes() : 0;
    return 0;
}

struct Inputs {
    std::vector<Vec3> wi, wo;
    std::vector<std::array<double, 2>> u;
    std::vector<rt::Float3> fi, fo;
    std::vector<float> fu;
    std::vector<Vec3> gi, go;  // fi, fo in double
};

Inputs inputs(std::size_t n) {
    const bench::Pairs p = bench::uniform_pairs(n);
    Inputs in{p.wi, p.wo, std::vector<std::array<double, 2>>(n), std::vector<rt::Float3>(n), std::vector<rt::Float3>(n),
              std::vector<float>(2 * n), std::vector<Vec3>(n), std::vector<Vec3>(n)};
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (std::size_t k = 0; k < n; ++k) {
        in.fu[2 * k] = std::min(u(rng), 0x1.fffffep-1f), in.fu[2 * k + 1] = std::min(u(rng), 0x1.fffffep-1f);
        in.u[k] = {in.fu[2 * k], in.fu[2 * k + 1]};
        in.fi[k] = {static_cast<float>(in.wi[k].x), static_cast<float>(in.wi[k].y), static_cast<float>(in.wi[k].z)};
        in.fo[k] = {static_cast<float>(in.wo[k].x), static_cast<float>(in.wo[k].y), static_cast<float>(in.wo[k].z)};
        in.gi[k] = {in.fi[k].x, in.fi[k].y, in.fi[k].z}, in.go[k] = {in.fo[k].x, in.fo[k].y, in.fo[k].z};
    }
    return in;
}

// Seconds per call of `calls` calls of f, run once untimed first: the library and the runtime each read
// their own copy of the data, and a copy too large for the caches (the 35 MB table) would otherwise be
// faster for whichever of them ran just before on the same directions.
template <typename F>
double per_call(F&& f, std::size_t calls) {
    f();
    const auto t0 = Clock::now();
    f();
    return seconds(t0, Clock::now()) / static_cast<double>(calls);
}

[[noreturn]] void usage() {
    std::fprintf(stderr, "usage: runtime_bench [--reps N] [--spec SPEC]... FILES...\n");
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) try {
    int reps = 9;
    std::vector<std::string> specs, files;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--reps" && i + 1 < argc) reps = std::atoi(argv[++i]);
        else if (a == "--spec" && i + 1 < argc) specs.push_back(argv[++i]);
        else if (!a.empty() && a[0] != '-') files.push_back(a);
        else usage();
    }
    if (files.empty() || reps < 1) usage();
    if (specs.empty()) specs = {"svd:rank=10,space=cos,colour=shared,res=50x40x14,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16"};
    bench::TempDir dir;
    const std::size_t n = std::size_t{1} << 16, single = std::size_t{1} << 15;
    const Inputs in = inputs(n);
    std::printf("file,spec,bytes,sampler_bytes,brdfz_bytes,brdfzrt_bytes,load_ms,open_ms,first_sample_us,first_allocations,"
                "first_threads,memory_bytes,eval_one_ns,eval_one_ratio,pdf_one_ns,pdf_one_ratio,sample_one_ns,"
                "sample_one_ratio,eval_batch_ns,eval_batch_ratio,sample_batch_ns,sample_batch_ratio,eval_one_f64_ns,"
                "eval_one_f64_ratio,pdf_one_f64_ns,pdf_one_f64_ratio,sample_one_f64_ns,sample_one_f64_ratio,eval_same_ratio,pdf_same_ratio,sample_same_ratio\n");
    for (const std::string& file : files) {
        const Loaded source = load(file);
        for (const std::string& spec : specs) {
            const Compressed c = compress(*source.brdf, spec, with_file_access({}));
            const std::string stored = (dir.path() / "m.brdfz").string(), flat = (dir.path() / "m.brdfzrt").string();
            container::write(stored, *c.brdf);
            runtime_layout::write(flat, *c.brdf);
            // Load until ready to sample, and the first sample: a fresh material each rep.
            std::vector<double> load_s, open_s, first_s;
            std::size_t first_alloc = 0, memory = 0;
            int first_threads = 0;
            for (int r = 0; r < reps; ++r) {
                const std::size_t heap0 = heap_bytes();
                auto t0 = Clock::now();
                container::ReadResult m = container::read(stored);
                load_s.push_back(seconds(t0, Clock::now()));
                const int threads0 = thread_count();
                const std::size_t alloc0 = allocations.load();
                t0 = Clock::now();
                const BrdfSample s = m.brdf->sample(in.wo[r], 0.3, 0.6);
                first_s.push_back(seconds(t0, Clock::now()));
                first_alloc = allocations.load() - alloc0;
                first_threads = thread_count() - threads0;
                memory = heap_bytes() - heap0 + (s.pdf < 0.0 ? 1 : 0);
                t0 = Clock::now();
                const rt::Material opened = rt::Material::open(flat);
                open_s.push_back(seconds(t0, Clock::now()));
                if (!opened) return std::fprintf(stderr, "runtime_bench: %s does not open\n", flat.c_str()), 1;
            }
            std::string error;
            const rt::Material m = rt::Material::open(flat, &error);
            const Brdf& b = *c.brdf;
            std::vector<double> r_eval, r_pdf, r_sample, r_beval, r_bsample, r_eval64, r_pdf64, r_sample64, t_eval, t_pdf,
                t_sample, t_beval, t_bsample, t_eval64, t_pdf64, t_sample64, r_esame, r_psame, r_ssame;
            std::vector<Rgb> f(n);
            std::vector<BrdfSample> drawn(n);
            std::vector<rt::Rgb32> rf(n);
            std::vector<rt::Sample32> rs(n);
            double sink = 0.0;
            for (int r = 0; r < reps; ++r) {
                // Each comparison's two loops adjacent, in alternating order rep by rep.
                const auto timed = [&](auto&& lib, auto&& run, std::size_t calls) {
                    double tl = 0.0, tr = 0.0;
                    if (r % 2) tr = per_call(run, calls), tl = per_call(lib, calls);
                    else tl = per_call(lib, calls), tr = per_call(run, calls);
                    return std::pair{tl, tr};
                };
                const auto lib_eval = [&](const std::vector<Vec3>& wi, const std::vector<Vec3>& wo) {
                    return [&] { for (std::size_t k = 0; k < single; ++k) sink += b.eval(wi[k], wo[k])[1]; };
                };
                const auto lib_pdf = [&](const std::vector<Vec3>& wo, const std::vector<Vec3>& wi) {
                    return [&] { for (std::size_t k = 0; k < single; ++k) sink += b.pdf(wo[k], wi[k]); };
                };
                const auto lib_sample = [&](const std::vector<Vec3>& wo) {
                    return [&] { for (std::size_t k = 0; k < single; ++k) sink += b.sample(wo[k], in.u[k][0], in.u[k][1]).pdf; };
                };
                const auto rt_eval = [&] { for (std::size_t k = 0; k < single; ++k) sink += m.eval(in.fi[k], in.fo[k]).g; };
                const auto rt_pdf = [&] { for (std::size_t k = 0; k < single; ++k) sink += m.pdf(in.fo[k], in.fi[k]); };
                const auto rt_sample = [&] { for (std::size_t k = 0; k < single; ++k) sink += m.sample(in.fo[k], in.fu[2 * k], in.fu[2 * k + 1]).pdf; };
                const auto [le, re] = timed(lib_eval(in.wi, in.wo), rt_eval, single);
                const auto [lg, re_same] = timed(lib_eval(in.gi, in.go), rt_eval, single);
                const auto [le2, re64] = timed(lib_eval(in.wi, in.wo), [&] { for (std::size_t k = 0; k < single; ++k) sink += m.eval(in.wi[k], in.wo[k])[1]; }, single);
                const auto [lp, rp] = timed(lib_pdf(in.wo, in.wi), rt_pdf, single);
                const auto [lpg, rp_same] = timed(lib_pdf(in.go, in.gi), rt_pdf, single);
                const auto [lp2, rp64] = timed(lib_pdf(in.wo, in.wi), [&] { for (std::size_t k = 0; k < single; ++k) sink += m.pdf(in.wo[k], in.wi[k]); }, single);
                const auto [ls, rs1] = timed(lib_sample(in.wo), rt_sample, single);
                const auto [lsg, rs_same] = timed(lib_sample(in.go), rt_sample, single);
                const auto [ls2, rs64] = timed(lib_sample(in.wo), [&] { for (std::size_t k = 0; k < single; ++k) sink += m.sample(in.wo[k], in.u[k][0], in.u[k][1]).pdf; }, single);
                const auto [lbe, rbe] = timed([&] { b.eval(std::span<const Vec3>(in.wi), std::span<const Vec3>(in.wo), std::span(f)); },
                                              [&] { m.eval(in.fi.data(), in.fo.data(), rf.data(), n); }, n);
                const auto [lbs, rbs] = timed([&] { b.sample(std::span<const Vec3>(in.wo), std::span<const std::array<double, 2>>(in.u), std::span(drawn)); },
                                              [&] { m.sample(in.fo.data(), in.fu.data(), rs.data(), n); }, n);
                r_eval.push_back(le / re), r_pdf.push_back(lp / rp), r_sample.push_back(ls / rs1);
                r_beval.push_back(lbe / rbe), r_bsample.push_back(lbs / rbs), r_eval64.push_back(le2 / re64);
                r_pdf64.push_back(lp2 / rp64), r_sample64.push_back(ls2 / rs64);
                r_esame.push_back(lg / re_same), r_psame.push_back(lpg / rp_same), r_ssame.push_back(lsg / rs_same);
                t_eval.push_back(re), t_pdf.push_back(rp), t_sample.push_back(rs1), t_beval.push_back(rbe), t_bsample.push_back(rbs);
                t_eval64.push_back(re64), t_pdf64.push_back(rp64), t_sample64.push_back(rs64);
                sink += f[r][0] + drawn[r].pdf + rf[r].r + rs[r].pdf;
            }
            const std::string name = file.substr(file.find_last_of('/') + 1);
            std::printf("%s,\"%s\",%zu,%zu,%ju,%ju,%.3f,%.3f,%.1f,%zu,%d,%zu,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.1f,%.2f,%.2f,%.2f,%.2f\n",
                        name.c_str(), spec.c_str(), b.nbytes(), sampler_bytes(*c.brdf),
                        static_cast<std::uintmax_t>(std::filesystem::file_size(stored)),
                        static_cast<std::uintmax_t>(std::filesystem::file_size(flat)), 1e3 * bench::median(load_s),
                        1e3 * bench::median(open_s), 1e6 * bench::median(first_s), first_alloc, first_threads, memory,
                        1e9 * bench::median(t_eval), bench::median(r_eval), 1e9 * bench::median(t_pdf), bench::median(r_pdf),
                        1e9 * bench::median(t_sample), bench::median(r_sample), 1e9 * bench::median(t_beval),
                        bench::median(r_beval), 1e9 * bench::median(t_bsample), bench::median(r_bsample),
                        1e9 * bench::median(t_eval64), bench::median(r_eval64), 1e9 * bench::median(t_pdf64),
                        bench::median(r_pdf64), 1e9 * bench::median(t_sample64), bench::median(r_sample64),
                        bench::median(r_esame), bench::median(r_psame), bench::median(r_ssame));
            std::fprintf(stderr, "[%g]\n", sink);
            std::fflush(stdout);
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "runtime_bench: %s\n", e.what());
    return 1;
}
