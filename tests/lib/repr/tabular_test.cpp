#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <tuple>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/repr/tabular.h"
#include "detail/simd.h"

using namespace brdfz;

namespace {

// MERL's published lookup (BRDFRead.cpp, Matusik et al. 2003), restated from its description: spherical
// angles -> vectors, half vector, θh/φh by acos/atan2, wi rotated by -φh about z and -θh about y with
// Rodrigues' formula, θd/φd by acos/atan2, then the three index functions.
struct MerlReference {
    static void rotate(const double v[3], const double axis[3], double angle, double out[3]) {
        const double c = std::cos(angle), s = std::sin(angle);
        const double d = (axis[0] * v[0] + axis[1] * v[1] + axis[2] * v[2]) * (1.0 - c);
        const double cross[3] = {axis[1] * v[2] - axis[2] * v[1], axis[2] * v[0] - axis[0] * v[2],
                                 axis[0] * v[1] - axis[1] * v[0]};
        for (int k = 0; k < 3; ++k) out[k] = v[k] * c + axis[k] * d + cross[k] * s;
    }
    static void normalize(double v[3]) {
        const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; ++k) v[k] /= n;
    }
    static int theta_half_index(double th) {
        if (th <= 0.0) return 0;
        const int i = static_cast<int>(std::sqrt(th / (M_PI / 2.0) * 90 * 90));
        return std::clamp(i, 0, 89);
    }
    // MERL's code casts acos of a rounded cosine just above 1 (wi == wo), NaN, to int: undefined
    // behaviour, which on x86 gives INT_MIN, clamped to bin 0. Bin 0 without the undefined cast.
    static int theta_diff_index(double td) {
        if (std::isnan(td)) return 0;
        return std::clamp(static_cast<int>(td / (M_PI * 0.5) * 90), 0, 89);
    }
    static int phi_diff_index(double pd) {
        if (pd < 0.0) pd += M_PI;
        return std::clamp(static_cast<int>(pd / M_PI * 360 / 2), 0, 179);
    }
    static int index(double ti, double pi, double to, double po) {
        double in[3] = {std::sin(ti) * std::cos(pi), std::sin(ti) * std::sin(pi), std::cos(ti)};
        double out[3] = {std::sin(to) * std::cos(po), std::sin(to) * std::sin(po), std::cos(to)};
        normalize(in);
        normalize(out);
        double h[3] = {(in[0] + out[0]) / 2, (in[1] + out[1]) / 2, (in[2] + out[2]) / 2};
        normalize(h);
        const double th = std::acos(h[2]), ph = std::atan2(h[1], h[0]);
        const double z[3] = {0, 0, 1}, y[3] = {0, 1, 0};
        double tmp[3], diff[3];
        rotate(in, z, -ph, tmp);
        rotate(tmp, y, -th, diff);
        const double td = std::acos(diff[2]), pd = std::atan2(diff[1], diff[0]);
        return phi_diff_index(pd) + 180 * (theta_diff_index(td) + 90 * theta_half_index(th));
    }
};

// A 90x90x180 table whose value at every bin is the bin's index (exact in float32: < 2^24).
TabularBrdf index_table(Lookup lookup) {
    Table t(GridSpec{});
    for (std::size_t b = 0; b < t.bins(); ++b) {
        const double v = static_cast<double>(b);
        t.set(b, {v, v, v});
    }
    return TabularBrdf(std::move(t), lookup);
}

}  // namespace

TEST_CASE("nearest lookup picks MERL's bin, bit for bit", "[tabular][merl]") {
    const TabularBrdf brdf = index_table(Lookup::Nearest);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> theta(0.0, M_PI / 2), phi(-M_PI, M_PI);
    auto check = [&](double ti, double pi, double to, double po) {
        const Vec3 wi = spherical_direction(ti, pi), wo = spherical_direction(to, po);
        if (!(wi.z > 0 && wo.z > 0)) return true;
        return brdf.eval(wi, wo)[0] == static_cast<double>(MerlReference::index(ti, pi, to, po));
    };
    int mismatches = 0;
    for (int k = 0; k < 1000000; ++k) mismatches += !check(theta(rng), phi(rng), theta(rng), phi(rng));
    CHECK(mismatches == 0);

    // Special pairs: normal incidence, mirror, grazing.
    CHECK(check(0, 0, 0, 0));
    CHECK(check(0.7, 0.2, 0.7, 0.2 + M_PI));
    CHECK(check(M_PI / 2 - 1e-9, 0.5, M_PI / 2 - 1e-9, 2.5));
    CHECK(check(M_PI / 2 - 1e-9, 0.5, 0.2, 0.5));

    // wi == wo: θd = 0, where φd is undefined and MERL's own φd is rounding noise (atan2 of two
    // residues). Every φd bin there describes the same configuration; θh and θd bins must agree.
    for (double ti : {1e-12, 0.3, 1.2, M_PI / 2 - 1e-6}) {
        const Vec3 w = spherical_direction(ti, 1.0);
        const auto ours = static_cast<long>(brdf.eval(w, w)[0]);
        const long ref = MerlReference::index(ti, 1.0, ti, 1.0);
        CHECK(ours / 180 == ref / 180);
    }
}

namespace {

// Values that change along every axis, distinct per channel: 1 + ih + 10 id + 100 cos(2π ip / n), times 1, 2, 3.
Table ramp_table(const GridSpec& g) {
    Table t(g);
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const double v = 1.0 + ih + 10.0 * id + 100.0 * std::cos(2 * M_PI * ip / g.n_phi_d);
                t.set(g.index(ih, id, ip), {v, 2 * v, 3 * v});
            }
    return t;
}

}  // namespace

TEST_CASE("linear lookup reproduces samples, interpolates between them, skips invalid ones", "[tabular]") {
    const GridSpec g{8, 8, 16};
    const Table t = ramp_table(g);
    TabularBrdf brdf(t, Lookup::Linear);
    auto at = [&](int ih, int id, int ip, int c = 0) { return static_cast<double>(t.at(g.index(ih, id, ip), c)); };

    auto pair_at = [&](double uh, double ud, double up) {
        return from_half_diff({axis::u_to_theta_h(uh, g.n_theta_h), 0.3, axis::u_to_theta_d(ud, g.n_theta_d),
                               axis::u_to_phi_d(up, g.n_phi_d)});
    };
    SECTION("at a sample") {
        const auto [wi, wo] = pair_at(3.5, 2.5, 5.5);  // bin centres
        const Rgb f = brdf.eval(wi, wo);
        CHECK(f[0] == Approx(at(3, 2, 5, 0)).epsilon(1e-9));
        CHECK(f[2] == Approx(at(3, 2, 5, 2)).epsilon(1e-9));
    }
    SECTION("halfway along θd") {
        const auto [wi, wo] = pair_at(3.5, 3.0, 5.5);
        CHECK(brdf.eval(wi, wo)[0] == Approx(0.5 * (at(3, 2, 5, 0) + at(3, 3, 5, 0))).epsilon(1e-9));
    }
    SECTION("φd wraps around by reciprocity") {
        const auto [wi, wo] = pair_at(3.5, 2.5, 0.0);  // between the last and the first φd sample
        CHECK(brdf.eval(wi, wo)[0] == Approx(0.5 * (at(3, 2, 15, 0) + at(3, 2, 0, 0))).epsilon(1e-9));
    }
    SECTION("an invalid neighbour is skipped, not read as zero") {
        Table holed = t;
        holed.invalidate(g.index(3, 3, 5));
        TabularBrdf b(std::move(holed), Lookup::Linear);
        const auto [wi, wo] = pair_at(3.5, 3.0, 5.5);
        CHECK(b.eval(wi, wo)[0] == Approx(at(3, 2, 5, 0)).epsilon(1e-9));
    }
    SECTION("the last bin, whose three floats are read as four (the sanitizer run checks the bounds)") {
        const GridSpec one{1, 1, 16};  // the last bin of a finer grid is below the horizon
        const Table last = ramp_table(one);
        const TabularBrdf b(last, Lookup::Linear);
        const auto [wi, wo] = from_half_diff({axis::u_to_theta_h(0.5, 1), 0.3, axis::u_to_theta_d(0.5, 1),
                                              axis::u_to_phi_d(15.5, 16)});
        const std::vector<Vec3> wis{wi}, wos{wo};
        std::vector<Rgb> f(1);
        b.eval(wis, wos, f);
        for (int c = 0; c < 3; ++c) {
            const double expected = last.at(one.index(0, 0, 15), c);
            CHECK(b.eval(wi, wo)[c] == Approx(expected).epsilon(1e-9));
            CHECK(f[0][c] == Approx(expected).epsilon(1e-9));
        }
    }
    SECTION("bin start moves the samples") {
        Table start(GridSpec{8, 8, 16, BinPosition::Start});
        std::copy(t.data(), t.data() + 3 * t.bins(), start.data());
        TabularBrdf b(std::move(start), Lookup::Linear);
        const auto [wi, wo] = pair_at(3.0, 2.0, 5.0);  // bin starts
        CHECK(b.eval(wi, wo)[1] == Approx(at(3, 2, 5, 1)).epsilon(1e-9));
    }
}

TEST_CASE("tabular eval is finite and zero below the horizon for any input", "[tabular][conventions]") {
    const TabularBrdf brdf = index_table(Lookup::Linear);
    const double nan = std::nan("");
    const Vec3 up{0, 0, 1};
    const Vec3 bad[] = {{nan, 0, 1}, {0, nan, 1}, {0, 0, nan}, {INFINITY, 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}};
    for (const Vec3& v : bad) {
        for (Lookup l : {Lookup::Nearest, Lookup::Linear}) {
            TabularBrdf b = index_table(l);
            for (const Rgb& f : {b.eval(v, up), b.eval(up, v), b.eval(v, v)})
                for (double c : f) CHECK(std::isfinite(c));
        }
    }
    CHECK(brdf.eval(Vec3{0, 0, -1}, up) == Rgb{0, 0, 0});
    CHECK(brdf.eval(up, Vec3{0.6, 0, -0.8}) == Rgb{0, 0, 0});

    // Batch and single evaluation agree, and eval_cos multiplies by cosθi.
    std::mt19937_64 rng(3);
    std::normal_distribution<double> n;
    std::vector<Vec3> wi(1000), wo(1000);
    for (std::size_t k = 0; k < wi.size(); ++k) {
        wi[k] = normalize({n(rng), n(rng), n(rng)});
        wo[k] = normalize({n(rng), n(rng), n(rng)});
    }
    std::vector<Rgb> f(wi.size()), fc(wi.size());
    brdf.eval(wi, wo, f);
    brdf.eval_cos(wi, wo, fc);
    for (std::size_t k = 0; k < wi.size(); ++k) {
        CHECK(f[k] == brdf.eval(wi[k], wo[k]));
        CHECK(fc[k][1] == Approx(f[k][1] * std::max(wi[k].z, 0.0)));
    }
    std::vector<Rgb> short_out(3);
    CHECK_THROWS_AS(brdf.eval(wi, wo, short_out), std::exception);
}

TEST_CASE("a warped θd axis: exact inverse, linear at w = 0, bins denser towards grazing", "[tabular][warp]") {
    constexpr int n = 40;
    for (double t = 0.0; t <= M_PI / 2; t += 0.01) CHECK(axis::theta_d_to_u(t, n, 0.0) == axis::theta_d_to_u(t, n));
    CHECK(axis::u_to_theta_d(7.5, n, 0.0) == axis::u_to_theta_d(7.5, n));
    for (double w : {0.2, 0.6, 0.95}) {
        INFO("w = " << w);
        CHECK(axis::theta_d_to_u(0.0, n, w) == 0.0);
        CHECK(axis::theta_d_to_u(M_PI / 2, n, w) == Approx(n).epsilon(1e-15));
        double last = -1.0;
        for (double t = 0.0; t <= M_PI / 2; t += 0.01) {
            const double u = axis::theta_d_to_u(t, n, w);
            CHECK(u > last);
            last = u;
            CHECK(axis::u_to_theta_d(u, n, w) == Approx(t).margin(1e-13));
        }
        // The last bin is narrower than the linear axis's, the first wider, by the map's slope.
        const GridSpec g{8, n, 8, BinPosition::Centre, w};
        const double slope_end = (1 - w) + w * M_PI / 2;
        CHECK(M_PI / 2 - g.theta_d_at(n - 1) == Approx(0.5 / n * (M_PI / 2) / slope_end).epsilon(0.01));
        CHECK(g.theta_d_at(0) > GridSpec{8, n, 8}.theta_d_at(0));
    }
    CHECK_THROWS_AS((GridSpec{8, 8, 8, BinPosition::Centre, 0.96}.validate()), ValueError);
    CHECK_THROWS_AS((GridSpec{8, 8, 8, BinPosition::Centre, -0.1}.validate()), ValueError);
    CHECK_THROWS_AS((GridSpec{8, 8, 8, BinPosition::Centre, std::nan("")}.validate()), ValueError);
}

TEST_CASE("lookups on a warped θd axis read the samples where the axis puts them", "[tabular][warp]") {
    const GridSpec g{8, 8, 16, BinPosition::Centre, 0.7};
    const Table t = ramp_table(g);
    const TabularBrdf linear(t, Lookup::Linear), nearest(t, Lookup::Nearest);
    auto at = [&](int ih, int id, int ip) { return static_cast<double>(t.at(g.index(ih, id, ip), 0)); };
    auto pair_at = [&](double uh, double ud, double up) {
        return from_half_diff({axis::u_to_theta_h(uh, g.n_theta_h), 0.3, axis::u_to_theta_d(ud, g.n_theta_d, 0.7),
                               axis::u_to_phi_d(up, g.n_phi_d)});
    };
    for (int id = 0; id < g.n_theta_d; ++id) {
        const auto [wi, wo] = pair_at(3.5, id + 0.5, 5.5);
        if (!(wi.z > 0 && wo.z > 0)) continue;
        CHECK(linear.eval(wi, wo)[0] == Approx(at(3, id, 5)).epsilon(1e-9));
        const auto [wi1, wo1] = pair_at(3.5, id + 0.95, 5.5);
        if (!(wi1.z > 0 && wo1.z > 0)) continue;
        CHECK(nearest.eval(wi1, wo1)[0] == at(3, id, 5));
        if (id + 1 < g.n_theta_d) {
            const auto [wi2, wo2] = pair_at(3.5, id + 1.0, 5.5);
            if (!(wi2.z > 0 && wo2.z > 0)) continue;
            CHECK(linear.eval(wi2, wo2)[0] == Approx(0.5 * (at(3, id, 5) + at(3, id + 1, 5))).epsilon(1e-7));
        }
    }
    // Batch eval (the vectorised coordinates) agrees with single-pair eval.
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<Vec3> wi, wo;
    for (int k = 0; k < 1000; ++k) {
        wi.push_back(spherical_direction(u(rng) * M_PI / 2, u(rng) * 2 * M_PI));
        wo.push_back(spherical_direction(u(rng) * M_PI / 2, u(rng) * 2 * M_PI));
    }
    for (const TabularBrdf* b : {&linear, &nearest}) {
        std::vector<Rgb> out(wi.size());
        b->eval(wi, wo, out);
        for (std::size_t k = 0; k < wi.size(); ++k)
            for (int c = 0; c < 3; ++c) CHECK(out[k][c] == Approx(b->eval(wi[k], wo[k])[c]).epsilon(1e-7));
    }
    CHECK_THAT(linear.describe(), Catch::Contains("theta_d warp 0.7"));
}

// The batch kernel (detail/table_lookup.h) is built twice, for SSE2 and for AVX2 without FMA: both must
// give the one-pair eval's values, bit for bit, for float32 tables (both lookups) and compact tables, on
// a table with invalid bins, for pairs that take the kernel's fallbacks (φd ill-conditioned: wi = wo, the
// normal) and for bad input.
TEST_CASE("table eval batches: each value is the one-pair eval's, in both builds", "[tabular][compact][kernels][qemu]") {
    Table t(GridSpec{});
    for (std::size_t b = 0; b < t.bins(); ++b) {
        const double v = 1.0 + std::sin(0.001 * static_cast<double>(b));
        if (b % 7 == 3 || b / 180 % 90 > 80) continue;  // invalid: scattered bins and grazing θd
        t.set(b, {v, 2.0 * v, 0.5 + 0.25 * v});
    }
    TabularBrdf linear(std::move(t));
    TabularBrdf nearest(Table(linear.table()), Lookup::Nearest);
    const Compressed f16 = compress(linear, "tabular:res=45x45x90,dtype=f16");
    const Compressed u8 = compress(linear, "tabular:res=45x45x90,dtype=u8log");

    std::mt19937_64 rng(11);
    std::normal_distribution<double> n;
    std::vector<Vec3> wi(1000), wo(1000);  // not a multiple of the 64-pair block
    for (std::size_t k = 0; k < wi.size(); ++k) {
        wi[k] = normalize({n(rng), n(rng), n(rng)});
        wo[k] = normalize({n(rng), n(rng), std::fabs(n(rng))});
    }
    const double nan = std::nan("");
    const Vec3 up{0, 0, 1}, tilted = normalize({0.3, -0.2, 0.9});
    wi[1] = wo[1] = tilted;                        // θd = 0
    wi[2] = wo[2] = up;                            // θh = θd = 0
    wi[3] = normalize({-0.3, 0.2, 0.9}), wo[3] = tilted;  // θh = 0
    wi[4] = {nan, 0, 1}, wo[5] = {0, 0, nan}, wi[6] = {INFINITY, 0, 1}, wi[7] = {0, 0, 0}, wi[8] = {0, 0, -1};
    if (detail::simd_level() < detail::Simd::Avx2Fma) WARN("no AVX2 on this CPU: both runs use the SSE2 kernel");
    for (const auto& [b, simd] : {std::tuple{static_cast<const Brdf*>(&linear), detail::Simd::Avx2Fma},
                                  std::tuple{static_cast<const Brdf*>(&linear), detail::Simd::Sse2},
                                  std::tuple{static_cast<const Brdf*>(&nearest), detail::Simd::Avx2Fma},
                                  std::tuple{static_cast<const Brdf*>(&nearest), detail::Simd::Sse2},
                                  std::tuple{static_cast<const Brdf*>(f16.brdf.get()), detail::Simd::Avx2Fma},
                                  std::tuple{static_cast<const Brdf*>(f16.brdf.get()), detail::Simd::Sse2},
                                  std::tuple{static_cast<const Brdf*>(u8.brdf.get()), detail::Simd::Avx2Fma},
                                  std::tuple{static_cast<const Brdf*>(u8.brdf.get()), detail::Simd::Sse2}}) {
        INFO(b->describe() << (simd == detail::Simd::Sse2 ? ", SSE2 kernel" : ", AVX2 kernel"));
        std::vector<Rgb> out(wi.size());
        detail::simd_cap = simd;
        b->eval(wi, wo, out);
        detail::simd_cap = detail::Simd::Avx512;
        std::size_t positive = 0;
        for (std::size_t k = 0; k < wi.size(); ++k) {
            INFO(k);
            const Rgb f = b->eval(wi[k], wo[k]);
            detail::simd_cap = detail::Simd::Sse2;  // the one-pair eval has both builds too
            const Rgb f_sse2 = b->eval(wi[k], wo[k]);
            detail::simd_cap = detail::Simd::Avx512;
            for (int c = 0; c < 3; ++c) {
                REQUIRE(std::isfinite(out[k][c]));
                REQUIRE(out[k][c] == f[c]);
                REQUIRE(f_sse2[c] == f[c]);
            }
            positive += f[0] > 0.0;
        }
        CHECK(positive > wi.size() / 3);  // the pairs above the horizon, less those on invalid bins only
        if (b != &nearest)  // a nearest bin may be an invalid one; a linear lookup has valid neighbours
            for (std::size_t k = 1; k <= 3; ++k) CHECK(out[k][0] > 0.0);
    }
}

