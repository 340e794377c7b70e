// The baseline level's scalar form: x86-64 CPUs without SSE4.2 run the kernels' Highway SCALAR builds
// (lib/runtime/src/hwy_dispatch.h). Here, on a CPU with SSE4.2, they run with the SSE4 builds turned
// off (runtime/kernels/simd.h: baseline_sse4) and must give the SSE4 builds' bits: the tables' eval and
// sample (the half-vector sampler's block draws), the factored eval and the RGL kernels.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/repr/tabular.h"
#include "simd_levels.h"

using namespace brdfz;

namespace {

struct Run {
    std::vector<Rgb> f;
    std::vector<double> pdf;
    std::vector<BrdfSample> s;
};

// The baseline level, in its SSE4 build or its scalar form, for the scope.
struct BaselineForm {
    explicit BaselineForm(bool sse4) : cap(detail::Simd::Sse2) { runtime::kernels::baseline_sse4 = sse4; }
    ~BaselineForm() { runtime::kernels::baseline_sse4 = true; }
    test::SimdCap cap;
};

template <typename Make>
Run run(bool sse4, Make make) {
    const BaselineForm form(sse4);
    const auto brdf = make();  // representations take their kernels' builds when made
    std::mt19937_64 rng(5);
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const std::size_t count = 777;  // not a multiple of any block
    std::vector<Vec3> wi(count), wo(count);
    std::vector<std::array<double, 2>> u(count);
    for (std::size_t k = 0; k < count; ++k) {
        wi[k] = normalize({n(rng), n(rng), std::fabs(n(rng))});
        wo[k] = normalize({n(rng), n(rng), std::fabs(n(rng))});
        u[k] = {u01(rng), u01(rng)};
    }
    Run r{std::vector<Rgb>(count), std::vector<double>(count), std::vector<BrdfSample>(count)};
    brdf->eval(wi, wo, r.f);
    brdf->pdf(wo, wi, r.pdf);
    brdf->sample(wo, u, r.s);
    return r;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(T) * a.size()) == 0;
}

template <typename Make>
void check_forms(Make make) {
    const Run sse4 = run(true, make), scalar = run(false, make);
    CHECK(same_bits(sse4.f, scalar.f));
    CHECK(same_bits(sse4.pdf, scalar.pdf));
    CHECK(same_bits(sse4.s, scalar.s));
    std::size_t positive = 0;
    for (const Rgb& f : sse4.f) positive += f[0] > 0.0;
    CHECK(positive > sse4.f.size() / 4);
}

// Small, so that the factorisations build quickly under the sanitizers.
Table glossy_table() {
    Table t(GridSpec{16, 16, 32});
    for (std::size_t b = 0; b < t.bins(); ++b) {
        if (b % 11 == 5) continue;  // invalid bins
        const double v = 1.0 + 4.0 * std::exp(-0.01 * static_cast<double>(b % 1000));
        t.set(b, {v, 0.5 * v, 0.25 + 0.1 * v});
    }
    return t;
}

}  // namespace

TEST_CASE("scalar form: the baseline level's SCALAR builds give its SSE4 builds' bits", "[kernels]") {
    if (!runtime::kernels::cpu_has_sse4()) {
        WARN("no SSE4.2 on this CPU (or not x86-64): the baseline level runs its only build");
        return;
    }
    const Table t = glossy_table();
    SECTION("tables and factorisations") {
        for (const char* spec : {"tabular:res=16x16x32", "tabular:res=16x16x32,dtype=f16",
                                 "tabular:res=16x16x32,dtype=u8log", "svd:rank=4,space=log,res=16x16x32",
                                 "svd:rank=3,space=cos,layout=hd_p,colour=shared,res=16x16x32"}) {
            INFO(spec);
            check_forms([&] { return compress(TabularBrdf(Table(t)), spec).brdf; });
        }
    }
    SECTION("nearest lookup") {
        check_forms([&] { return std::make_shared<TabularBrdf>(Table(t), Lookup::Nearest); });
    }
    SECTION("an RGL file") {
        const std::filesystem::path file = std::filesystem::path(BRDFZ_SHARED_DIR) / "data/rgl/satin_purple_rgb.bsdf";
        if (!std::filesystem::exists(file)) {
            WARN("skipped: " << file << " is missing (../shared)");
            return;
        }
        check_forms([&] { return rgl::read(file.string()).brdf; });
    }
}
