// brdfz::runtime against the library: every kind exported to the runtime layout gives the library's
// eval, pdf and sample in float32 (1e-5 relative) and double; bad layouts are refused with a line;
// directions are prepared as the library prepares them; calls allocate nothing; threads agree. A
// factorisation gives the library's bits at each level (kernels/factored.h).
#include <catch2/catch.hpp>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/formats/runtime_layout.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/pca.h"
#include "brdfz/runtime/crc32c.h"
#include "brdfz/runtime/runtime.h"
#include "brdfz/select.h"
#include "brdfz/tabulate.h"
#include "detail/simd.h"
#include "sample_stats.h"
#include "simd_levels.h"
#include "test_util.h"

using namespace brdfz;
namespace rt = brdfz::runtime;

// Allocations made on this thread, for the no-allocation check: the test binary's operator new counts
// them (every test runs with it; it allocates as the default one does). Every unaligned form is
// replaced, so that what one form allocates another frees (AddressSanitizer checks the pairing).
namespace {
thread_local std::size_t allocations = 0;
void* counted(std::size_t n) noexcept {
    ++allocations;
    return std::malloc(n ? n : 1);
}
}  // namespace
void* operator new(std::size_t n) {
    if (void* p = counted(n)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    if (void* p = counted(n)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return counted(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return counted(n); }
// GCC cannot tell that these replace the global forms, whose new is the malloc above.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace {

rt::Material exported(const Brdf& b) {
    const std::vector<unsigned char> bytes = runtime_layout::encode(b);
    std::string error;
    rt::Material m = rt::Material::from_memory(bytes.data(), bytes.size(), true, &error);
    INFO(error);
    REQUIRE(m);
    return m;
}

rt::Float3 to_float(const Vec3& v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }
Vec3 to_double(const rt::Float3& v) { return {v.x, v.y, v.z}; }

// The worst relative difference of a against b, where b is above `floor` (smaller values compare in
// absolute terms against the floor).
double relative(double a, double b, double floor) { return std::fabs(a - b) / std::max(std::fabs(b), floor); }

struct Agreement {
    double eval = 0, pdf = 0, weight = 0;
    std::size_t draws_differ = 0, draws = 0;
};

// n random pairs and draws, the runtime's float32 calls against the library's at the directions the
// runtime prepares from the floats (so both see the same input).
Agreement compare(const Brdf& b, const rt::Material& m, std::size_t n, std::uint64_t seed) {
    auto [wo, us] = test::random_views(n, seed);
    auto [wi, unused] = test::random_views(n, seed + 1);
    Agreement a;
    std::vector<Vec3> wis(n), wos(n);
    std::vector<rt::Float3> fi(n), fo(n);
    for (std::size_t k = 0; k < n; ++k) {
        fi[k] = to_float(wi[k]), fo[k] = to_float(wo[k]);
        wis[k] = to_double(fi[k]), wos[k] = to_double(fo[k]);
        prepare_direction(wis[k]), prepare_direction(wos[k]);
    }
    std::vector<Rgb> f(n);
    b.eval(std::span<const Vec3>(wis), std::span<const Vec3>(wos), std::span(f));
    double top = 0.0;
    for (const Rgb& x : f) top = std::max({top, x[0], x[1], x[2]});
    const double floor = 1e-6 * top;  // values near 0 after cancellation: against the data's scale
    std::vector<double> pdf(n);
    b.pdf(std::span<const Vec3>(wos), std::span<const Vec3>(wis), std::span(pdf));
    for (std::size_t k = 0; k < n; ++k) {
        const rt::Rgb32 r = m.eval(fi[k], fo[k]);
        a.eval = std::max({a.eval, relative(r.r, f[k][0], floor), relative(r.g, f[k][1], floor), relative(r.b, f[k][2], floor)});
        a.pdf = std::max(a.pdf, relative(m.pdf(fo[k], fi[k]), pdf[k], 1e-30));
        const float u1 = static_cast<float>(us[k][0]), u2 = static_cast<float>(us[k][1]);
        const rt::Sample32 s = m.sample(fo[k], u1, u2);
        const BrdfSample l = b.sample(wos[k], u1, u2);
        a.draws += l.pdf > 0.0;
        if ((s.pdf > 0.0f) != (l.pdf > 0.0)) {
            ++a.draws_differ;
            continue;
        }
        if (l.pdf == 0.0) continue;
        const double dw = std::max({std::fabs(s.wi.x - l.wi.x), std::fabs(s.wi.y - l.wi.y), std::fabs(s.wi.z - l.wi.z)});
        if (dw > 1e-5) {
            ++a.draws_differ;
            continue;
        }
        a.pdf = std::max(a.pdf, relative(s.pdf, l.pdf, 1e-30));
        const double wfloor = 1e-6 * (std::fabs(l.weight[0]) + std::fabs(l.weight[1]) + std::fabs(l.weight[2]) + 1e-30);
        a.weight = std::max({a.weight, relative(s.weight.r, l.weight[0], wfloor), relative(s.weight.g, l.weight[1], wfloor),
                             relative(s.weight.b, l.weight[2], wfloor)});
    }
    return a;
}

void check_agreement(const Brdf& b, std::size_t n) {
    const rt::Material m = exported(b);
    const Agreement a = compare(b, m, n, 17);
    INFO(b.describe() << ": eval " << a.eval << ", pdf " << a.pdf << ", weight " << a.weight << ", draws differing "
                      << a.draws_differ << " of " << a.draws);
    CHECK(a.eval <= 1e-5);
    CHECK(a.pdf <= 1e-5);
    CHECK(a.weight <= 1e-5);
    // A float u can land on the other side of a CDF step than the double the library draws from only
    // where they differ (never: the library is given the same float u): every draw is the same.
    CHECK(a.draws_differ == 0);
    CHECK(a.draws > n / 2);
}

CoatedDiffuse coated(double alpha) {
    CoatedDiffuseParams p;
    p.alpha = alpha;
    return CoatedDiffuse(p);
}

}  // namespace

TEST_CASE("runtime: every gridded kind agrees with the library (synthetic material)", "[runtime][qemu]") {
    const test::SimdCap sse2(detail::Simd::Sse2);
    const CoatedDiffuse source = coated(0.08);
    for (const char* spec : {"tabular:res=16x16x32", "tabular:res=16x16x32,dtype=f16,symmetry=none",
                             "tabular:res=16x16x16,dtype=u8log,symmetry=bilateral,lookup=nearest",
                             "bivariate:res=16x16,dtype=f16", "svd:rank=2,res=16x16x32,dtype=f16",
                             "nmf:rank=2,res=16x16x32,iterations=20,space=cbrt,layout=hd_p",
                             "svd:rank=3,res=16x12x16,colour=shared,space=cos,symmetry=bilateral,dwarp=0.8",
                             "tabular:res=12x12x16,phih=3,symmetry=bilateral,dtype=f16",
                             "svd:rank=2,res=12x12x16,phih=2,symmetry=none", "tabular:res=16x16x16,dtype=u8log,hwarp=3",
                             "svd:rank=2,res=16x16x16,space=cos,symmetry=bilateral,dtype=f16,hwarp=auto"}) {
        INFO(spec);
        check_agreement(*compress(source, spec).brdf, 20000);
    }
}

TEST_CASE("runtime: analytic models agree with the library", "[runtime][analytic][qemu]") {
    for (const char* text : {"lambert+ggx", "lambert+beckmann+ward", "lafortune3", "ggx_aniso+ashikhmin_shirley",
                             "lambert+ggx_conductor+blinn_phong+ggx_sep"}) {
        INFO(text);
        const Model model = Model::parse(text);
        check_agreement(AnalyticBrdf(model, model.defaults()), 20000);
        // The kind's default sampler, exported with the model.
        check_agreement(*AnalyticBrdf::with_compact_sampler(model, model.defaults()), 20000);
    }
}

// An analytic model carries the compact sampler's sections, or the lobe mixture's albedo table: one of
// the two, and a layout with neither is refused.
TEST_CASE("runtime: an analytic model's sampler is its compact sampler or its lobe mixture", "[runtime][analytic]") {
    const Model model = Model::parse("lambert+ggx");
    const auto compact = AnalyticBrdf::with_compact_sampler(model, model.defaults());
    const AnalyticBrdf lobes(model, model.defaults());
    const auto tags = [](const std::vector<unsigned char>& bytes) {
        std::vector<std::string> out;
        std::uint32_t n;
        std::memcpy(&n, bytes.data() + 24, 4);
        for (std::uint32_t i = 0; i < n; ++i) out.emplace_back(reinterpret_cast<const char*>(bytes.data() + 64 + 32 * i), 4);
        return out;
    };
    const std::vector<unsigned char> with_compact = runtime_layout::encode(*compact), with_lobes = runtime_layout::encode(lobes);
    const auto has = [&](const std::vector<unsigned char>& b, const char* tag) {
        const auto t = tags(b);
        return std::find(t.begin(), t.end(), tag) != t.end();
    };
    CHECK(has(with_compact, "SAMP"));
    CHECK(!has(with_compact, "ALBD"));
    CHECK(has(with_lobes, "ALBD"));
    CHECK(!has(with_lobes, "SAMP"));
    rt::Material m = rt::Material::from_memory(with_compact.data(), with_compact.size(), true);
    REQUIRE(m);
    CHECK(m.sampler_nbytes() == compact->compact_sampler()->nbytes() + 28);
    // The albedo table renamed away (checksum recomputed): read as a model with no sampler at all.
    std::vector<unsigned char> bad = with_lobes;
    const auto t = tags(bad);
    const std::size_t at = std::find(t.begin(), t.end(), "ALBD") - t.begin();
    std::memcpy(bad.data() + 64 + 32 * at, "ALBX", 4);
    const std::uint32_t crc = rt::crc32c(bad.data() + 64, bad.size() - 64);
    std::memcpy(bad.data() + 28, &crc, 4);
    std::string error;
    CHECK(!rt::Material::from_memory(bad.data(), bad.size(), true, &error));
    CHECK_THAT(error, Catch::Contains("ALBD") && Catch::Contains("missing"));
}

TEST_CASE("runtime: PCA materials and fine-sampled ones are exported with their compact sampler", "[runtime]") {
    test::TempDir dir;
    std::vector<Table> tables;
    for (double alpha : {0.2, 0.35, 0.5, 0.7}) {
        TabulateOptions t;
        t.grid = GridSpec{16, 16, 32};
        tables.push_back(tabulate(coated(alpha), t).table);
    }
    std::vector<const Table*> pointers;
    for (const Table& t : tables) pointers.push_back(&t);
    const std::string basis = (dir.path / "basis.brdfz").string();
    container::write_pca_basis(basis, train_pca_basis(pointers));
    const test::SimdCap sse2(detail::Simd::Sse2);
    const Compressed pca = compress(coated(0.4), "pca:basis=" + basis + ",k=2", with_file_access({}));
    check_agreement(*pca.brdf, 20000);
    // A fine sampler is not what the runtime carries: the export builds the compact one of the material.
    const Compressed fine = compress(coated(0.1), "tabular:res=16x16x32,sampler=fine");
    const rt::Material m = exported(*fine.brdf);
    const Compressed compact = compress(coated(0.1), "tabular:res=16x16x32");
    const Vec3 wo = normalize({0.3, -0.2, 0.8});
    const rt::Sample64 s = m.sample(wo, 0.4, 0.7);
    const BrdfSample l = compact.brdf->sample(wo, 0.4, 0.7);
    CHECK(s.pdf == l.pdf);
    CHECK(s.wi.x == l.wi.x);
}

namespace {

// The shared RGL car paint, or nothing (with a message) where ../shared is missing.
std::optional<Loaded> shared_paint() {
    const std::filesystem::path file = test::rgl_file("cc_ibiza_sunset");
    std::error_code ec;
    if (!std::filesystem::exists(file, ec)) {
        WARN("skipped: " << file << " missing (../shared)");
        return std::nullopt;
    }
    return load(file.string());
}

}  // namespace

TEST_CASE("runtime: the shared RGL files' compact representations agree with the library on 10^5 pairs",
          "[runtime][rgl][heavy]") {
    const std::optional<Loaded> source = shared_paint();
    if (!source) return;
    const test::SimdCap sse2(detail::Simd::Sse2);
    for (const char* spec :
         {"svd:rank=10,space=cos,colour=shared,res=50x40x14,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16",
          "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16",
          "tabular:res=90x90x180,symmetry=bilateral,dtype=f16", "tabular:res=32x32x64,symmetry=none,dtype=u8log",
          "tabular:res=45x45x90,symmetry=none", "bivariate:res=64x64", "nmf:rank=3,res=32x32x32,iterations=40",
          "tabular:res=24x24x32,phih=2,symmetry=none,dtype=f16", "analytic:lambert+ggx,starts=1"}) {
        INFO(spec);
        check_agreement(*compress(*source->brdf, spec).brdf, 100000);
    }
}

TEST_CASE("runtime: a source the layout does not hold is tabulated with φd whole unless it is reciprocal",
          "[runtime][rgl]") {
    const std::optional<Loaded> source = shared_paint();
    if (!source) return;
    REQUIRE(!is_reciprocal(*source->brdf));
    const test::TempDir dir;
    const std::string path = (dir.path / "rgl.brdfzrt").string();
    runtime_layout::write(path, *source->brdf);
    const Loaded exported = load(path);
    CHECK_THAT(exported.brdf->describe(), Catch::Contains("symmetry bilateral"));
    MetricOptions o;
    o.over = Over::Directions;
    // A reciprocal fold stores the mean of f(wi, wo) and f(wo, wi): 13 % off this file over directions.
    CHECK(compare(*source->brdf, *exported.brdf, o).cos_rmse_rel.mean < 0.02);
    // A reciprocal source keeps MERL's folded grid.
    runtime_layout::write(path, coated(0.1));
    CHECK_THAT(load(path).brdf->describe(), Catch::Contains("tabulated on 90x90x180") && !Catch::Contains("bilateral"));
}

TEST_CASE("runtime: bad layouts are refused with a line, never read", "[runtime][robustness]") {
    const std::vector<unsigned char> good = runtime_layout::encode(*compress(coated(0.1), "svd:rank=2,res=8x8x16").brdf);
    std::string error;
    REQUIRE(rt::Material::from_memory(good.data(), good.size(), true, &error));
    const auto refused = [&](std::vector<unsigned char> bytes, const char* why) {
        std::string e;
        const rt::Material m = rt::Material::from_memory(bytes.data(), bytes.size(), true, &e);
        INFO(why << ": " << e);
        CHECK(!m);
        CHECK(!e.empty());
        CHECK(e.find('\n') == std::string::npos);
        return e;
    };
    CHECK_THAT(refused({}, "empty"), Catch::Contains("not a brdfz runtime layout"));
    CHECK_THAT(refused(std::vector<unsigned char>(good.begin(), good.end() - 64), "truncated"), Catch::Contains("bytes"));
    std::vector<unsigned char> b = good;
    b[good.size() - 100] ^= 1;
    CHECK_THAT(refused(b, "flipped byte"), Catch::Contains("checksum"));
    b = good;
    b[8] = 3;  // version
    CHECK_THAT(refused(b, "newer version"), Catch::Contains("layout version 3"));
    b = good;
    b[0] = 'X';
    refused(b, "magic");
    // Every truncation and every single-byte change of the header and section table is refused or
    // read whole (the CRC covers all but the header, whose fields are each checked).
    for (std::size_t cut = 0; cut < good.size(); cut += 61) refused(std::vector<unsigned char>(good.begin(), good.begin() + cut), "cut");
    for (std::size_t at = 0; at < 64; ++at) {
        if (at >= 28 && at < 32) continue;  // the CRC itself: a changed one is the checksum's failure
        b = good;
        b[at] ^= 0x5A;
        const rt::Material m = rt::Material::from_memory(b.data(), b.size(), true, &error);
        if (m) CHECK(std::isfinite(m.eval(rt::Float3{0, 0.6f, 0.8f}, rt::Float3{0, -0.6f, 0.8f}).r));
    }
    CHECK_THAT(rt::Material::open("/nonexistent/x.brdfzrt", &error) ? std::string() : error, Catch::Contains("/nonexistent/x.brdfzrt"));
}

TEST_CASE("runtime: every build this CPU runs gives the baseline build's bits", "[runtime][kernels][qemu]") {
    const CoatedDiffuse source = coated(0.08);
    // Named, not bound: the lambda below captures them (clang 14 cannot capture structured bindings).
    const auto views = test::random_views(5000, 3);
    const std::vector<Vec3>& wo = views.first;
    const std::vector<std::array<double, 2>>& us = views.second;
    const std::vector<Vec3> wi = test::random_views(5000, 4).first;
    // Factorisations are not among them: their wide builds fuse multiply-adds (the next test).
    for (const char* spec : {"tabular:res=16x16x32,dtype=f16,symmetry=none", "tabular:res=16x16x32,lookup=nearest",
                             "tabular:res=12x12x16,phih=3,symmetry=bilateral", "analytic:lambert+ggx"}) {
        const Compressed c = compress(source, spec);
        // Each level's outputs as bytes: eval, pdf and draws of the float calls.
        const auto outputs = [&](detail::Simd level) {
            const test::SimdCap cap(level);
            const rt::Material m = exported(*c.brdf);  // builds are taken at open
            std::vector<float> out;
            for (std::size_t k = 0; k < wo.size(); ++k) {
                const rt::Float3 i = to_float(wi[k]), o = to_float(wo[k]);
                const rt::Rgb32 f = m.eval(i, o);
                const rt::Sample32 s = m.sample(o, static_cast<float>(us[k][0]), static_cast<float>(us[k][1]));
                out.insert(out.end(), {f.r, f.g, f.b, m.pdf(o, i), s.wi.x, s.wi.y, s.wi.z, s.pdf, s.weight.r, s.weight.g, s.weight.b});
            }
            return out;
        };
        const std::vector<float> base = outputs(detail::Simd::Sse2);
        REQUIRE(std::count_if(base.begin(), base.end(), [](float x) { return x > 0.0f; }) > 1000);
        for (detail::Simd level : test::simd_levels()) {
            INFO(spec << ", " << test::simd_label(level));
            CHECK(std::memcmp(outputs(level).data(), base.data(), base.size() * sizeof(float)) == 0);
        }
    }
}

TEST_CASE("runtime: a factorisation gives the library's bits at every level this CPU runs", "[runtime][qemu]") {
    const CoatedDiffuse source = coated(0.08);
    auto [wo, us] = test::random_views(5000, 5);
    const std::vector<Vec3> wi = test::random_views(5000, 6).first;
    // Separate colour grouped (rank 3) and not (rank 5), shared colour in both layouts, the three
    // spaces, and slices of a φh stack.
    for (const char* spec : {"svd:rank=3,res=16x12x16,space=log", "nmf:rank=5,res=12x12x16,iterations=10,space=cbrt",
                             "svd:rank=6,res=16x12x16,colour=shared,space=cos,layout=hd_p,symmetry=bilateral",
                             "svd:rank=2,res=12x12x16,phih=2,symmetry=none", "tabular:res=16x16x16,dtype=u8log,hwarp=3",
                             "svd:rank=2,res=16x16x16,space=cos,symmetry=bilateral,dtype=f16,hwarp=auto"}) {
        for (detail::Simd level : test::simd_levels()) {
            INFO(spec << ", " << test::simd_label(level));
            const test::SimdCap cap(level);
            const Compressed c = compress(source, spec);  // the library's builds are taken when it is made
            const rt::Material m = exported(*c.brdf);
            std::size_t nonzero = 0, differ = 0;
            for (std::size_t k = 0; k < wo.size(); ++k) {
                const Rgb lib = c.brdf->eval(wi[k], wo[k]);
                const rt::Rgb64 f = m.eval(wi[k], wo[k]);
                nonzero += lib[1] > 0.0;
                differ += std::memcmp(lib.data(), f.data(), sizeof f) != 0;
                const BrdfSample l = c.brdf->sample(wo[k], us[k][0], us[k][1]);
                const rt::Sample64 s = m.sample(wo[k], us[k][0], us[k][1]);
                differ += l.wi.x != s.wi.x || l.wi.y != s.wi.y || l.wi.z != s.wi.z || l.pdf != s.pdf ||
                          std::memcmp(l.weight.data(), s.weight.data(), sizeof s.weight) != 0;
            }
            CHECK(nonzero > 2000);
            CHECK(differ == 0);
        }
    }
}

TEST_CASE("runtime: directions are prepared as the library prepares them", "[runtime][qemu]") {
    const Compressed c = compress(coated(0.1), "tabular:res=16x16x32,dtype=f16");
    const rt::Material m = exported(*c.brdf);
    const Vec3 wi = normalize({0.2, 0.3, 0.8}), wo = normalize({-0.4, 0.1, 0.6});
    const rt::Rgb64 unit = m.eval(wi, wo);
    REQUIRE(unit[1] > 0.0);
    // Non-unit: normalised; NaN, infinite, zero: 0 and pdf 0, and a failed draw.
    const rt::Rgb64 scaled = m.eval(3.0 * wi, 0.5 * wo);
    for (int ch = 0; ch < 3; ++ch) CHECK(scaled[ch] == Approx(unit[ch]).epsilon(1e-12));
    for (const Vec3& bad : {Vec3{NAN, 0, 1}, Vec3{0, 0, 0}, Vec3{INFINITY, 0, 1}}) {
        CHECK(m.eval(bad, wo)[0] == 0.0);
        CHECK(m.eval(wi, bad)[0] == 0.0);
        CHECK(m.pdf(bad, wi) == 0.0);
        CHECK(m.pdf(wo, bad) == 0.0);
        CHECK(m.sample(bad, 0.3, 0.3).pdf == 0.0);
        // The library's single-pair calls alike.
        CHECK(c.brdf->eval(bad, wo)[0] == 0.0);
        CHECK(c.brdf->pdf(wo, bad) == 0.0);
        CHECK(c.brdf->sample(bad, 0.3, 0.3).pdf == 0.0);
    }
    const Rgb lib = c.brdf->eval(3.0 * wi, 0.5 * wo);
    for (int ch = 0; ch < 3; ++ch) CHECK(lib[ch] == Approx(c.brdf->eval(wi, wo)[ch]).epsilon(1e-12));
    CHECK(m.sample(wo, 1.0, 0.5).pdf == 0.0);
    CHECK(m.sample(wo, 0.5, -0.1).pdf == 0.0);
    CHECK(rt::Material().eval(wi, wo)[0] == 0.0);
}

TEST_CASE("runtime: calls allocate nothing, and threads sharing a material agree with one", "[runtime]") {
    const Compressed c = compress(coated(0.1), "svd:rank=3,res=16x16x32,dtype=f16,colour=shared,phih=2");
    const rt::Material m = exported(*c.brdf);
    // Named, not bound: a lambda below uses them, and clang 14 does not capture structured bindings.
    const auto views = test::random_views(4000, 3);
    const std::vector<Vec3>& wo = views.first;
    const std::vector<std::array<double, 2>>& us = views.second;
    std::vector<rt::Float3> fo(wo.size());
    for (std::size_t k = 0; k < wo.size(); ++k) fo[k] = to_float(wo[k]);
    const auto run = [&](std::vector<float>& out) {
        for (std::size_t k = 0; k < wo.size(); ++k) {
            const rt::Sample32 s = m.sample(fo[k], static_cast<float>(us[k][0]), static_cast<float>(us[k][1]));
            const rt::Rgb32 f = m.eval(s.wi, fo[k]);
            out[k] = s.pdf + m.pdf(fo[k], s.wi) + f.r + f.g + f.b;
        }
    };
    std::vector<float> serial(wo.size());
    const std::size_t before = allocations;
    run(serial);
    CHECK(allocations == before);
    std::vector<std::vector<float>> parallel(4, std::vector<float>(wo.size()));
    std::vector<std::thread> threads;
    for (auto& p : parallel) threads.emplace_back([&run, &p] { run(p); });
    for (auto& t : threads) t.join();
    for (const auto& p : parallel) CHECK(std::memcmp(p.data(), serial.data(), serial.size() * sizeof(float)) == 0);
}
