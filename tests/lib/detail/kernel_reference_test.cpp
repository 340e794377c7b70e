// The Highway builds of the kernels shared by the library and brdfz::runtime (lib/runtime/src/
// blend_lanes-inl.h, factor_lanes-inl.h) against their scalar references (runtime/kernels/grid.h:
// blend_linear; factored.h: factor_sums_reference, and the whole eval with it), bit for bit, at every
// level this CPU runs. This file is compiled once per Highway target (hwy/foreach_target.h), as the
// kernels' own files are.
#ifndef BRDFZ_TEST_KERNEL_REFERENCE_ONCE
#define BRDFZ_TEST_KERNEL_REFERENCE_ONCE
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "brdfz/runtime/kernels/factored.h"
#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/values.h"
#include "hwy_dispatch.h"
#include "simd_levels.h"

namespace brdfz::test::kernel_reference {

namespace k = runtime::kernels;

// float32 bins readable as four floats (the storage padded by one), so the vector builds load each
// corner as one vector (grid.h, FloatBins); Float32Values itself takes the lane-by-lane path.
struct PaddedFloat32Values : k::Float32Values {
    const float* floats(std::size_t bin) const { return data + 3 * bin; }
};

// The factor sums of one pair, every shape: grouped or not, 2 rows × 4 columns (h_dp) or 4 × 2 (hd_p).
struct SumsCase {
    int rows[4], cols[4];
    float rw[4], cw[4];
};

}  // namespace brdfz::test::kernel_reference
#endif  // BRDFZ_TEST_KERNEL_REFERENCE_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "lib/detail/kernel_reference_test.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "blend_lanes-inl.h"
#include "factor_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::test::kernel_reference::HWY_NAMESPACE {

template <typename Values>
[[gnu::flatten]] void BlendAll(const k::Grid& g, const Values& values, const k::Corners* c, std::size_t n, double* f) {
    for (std::size_t i = 0; i < n; ++i) k::HWY_NAMESPACE::BlendLanes::blend(g, values, c[i], f + 3 * i);
}
void BlendFloat32(const k::Grid& g, const float* data, const k::Corners* c, std::size_t n, double* f) {
    BlendAll(g, k::Float32Values{data}, c, n, f);
}
void BlendPadded(const k::Grid& g, const float* data, const k::Corners* c, std::size_t n, double* f) {
    BlendAll(g, PaddedFloat32Values{{data}}, c, n, f);
}

// y: 3 floats per case and shape, in the order (grouped, h_dp), (grouped, hd_p), (mixed, h_dp), (mixed, hd_p).
[[gnu::flatten]] void SumsAll(const k::FactorView& f, const SumsCase* c, std::size_t n, float* y) {
    using S = k::HWY_NAMESPACE::FactorLanes;
    for (std::size_t i = 0; i < n; ++i, y += 12) {
        S::sums<true, 2, 4>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y);
        S::sums<true, 4, 2>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 3);
        S::sums<false, 2, 4>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 6);
        S::sums<false, 4, 2>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 9);
    }
}
// The whole factored eval: coordinates, corners, sums and inverse transform, fused where the sums are.
[[gnu::flatten]] void EvalAll(const k::FactorView& f, const Vec3* wi, const Vec3* wo, std::size_t n,
                              double* out) {
    for (std::size_t i = 0; i < n; ++i) k::eval_factored<k::HWY_NAMESPACE::FactorLanes>(f, wi[i], wo[i], out + 3 * i);
}
int SumsLanes() { return k::HWY_NAMESPACE::FactorLanes::kLanes; }
bool SumsFused() { return k::HWY_NAMESPACE::FactorLanes::kFused; }

}  // namespace brdfz::test::kernel_reference::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace brdfz::test::kernel_reference {
namespace {

template <int W, bool Fused>
void reference_sums(const k::FactorView& f, const SumsCase* c, std::size_t n, float* y) {
    for (std::size_t i = 0; i < n; ++i, y += 12) {
        k::factor_sums_reference<W, Fused, true, 2, 4>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y);
        k::factor_sums_reference<W, Fused, true, 4, 2>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 3);
        k::factor_sums_reference<W, Fused, false, 2, 4>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 6);
        k::factor_sums_reference<W, Fused, false, 4, 2>(f, c[i].rows, c[i].rw, c[i].cols, c[i].cw, y + 9);
    }
}

// The reference's eval, compiled for no target: its fused multiply-adds are libm's std::fma.
template <int W, bool Fused>
void reference_eval(const k::FactorView& f, const Vec3* wi, const Vec3* wo, std::size_t n,
                    double* out) {
    for (std::size_t i = 0; i < n; ++i) k::eval_factored<k::ReferenceSums<W, Fused>>(f, wi[i], wo[i], out + 3 * i);
}

}  // namespace
}  // namespace brdfz::test::kernel_reference

using namespace brdfz;
using namespace brdfz::test::kernel_reference;

TEST_CASE("kernels: every build's channel blend gives blend_linear's bits", "[kernels][qemu]") {
    k::Grid g;
    g.n_theta_h = 9, g.n_theta_d = 7, g.n_phi_d = 12;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> value(0.0f, 2.0f);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    // One float past the last bin: the padded policy reads four a bin.
    std::vector<float> data(3 * g.bins() + 1, 0.0f);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 0; i < 3 * g.bins(); ++i) data[i] = unit(rng) < 0.1 ? nan : value(rng);
    // A block of bins invalid in every channel, so some pairs blend no valid corner (their value is 0).
    for (std::size_t bin = 0; bin < 2 * static_cast<std::size_t>(g.n_phi_d); ++bin)
        for (int c = 0; c < 3; ++c) data[3 * bin + c] = nan;
    const std::size_t n = 4000;
    std::vector<k::Corners> corners(n);
    const auto span = [&](int size) {
        const int i0 = static_cast<int>(unit(rng) * size) % size;
        return k::Span{i0, std::min(i0 + 1, size - 1), unit(rng)};
    };
    for (k::Corners& c : corners) c = {span(g.n_theta_h), span(g.n_theta_d), span(g.n_phi_d)};
    corners[0] = {{0, 0, 0.5}, {0, 1, 0.25}, {3, 4, 0.75}};  // all eight corners invalid
    std::vector<double> ref(3 * n), got(3 * n);
    for (std::size_t i = 0; i < n; ++i) k::blend_linear(g, k::Float32Values{data.data()}, corners[i], &ref[3 * i]);
    CHECK(ref[0] == 0.0);
    const auto blend_float32 = BRDFZ_HWY_BUILDS(BlendFloat32);
    const auto blend_padded = BRDFZ_HWY_BUILDS(BlendPadded);
    for (detail::Simd level : test::simd_levels()) {
        INFO(test::simd_label(level));
        for (const auto* builds : {&blend_float32, &blend_padded}) {
            std::fill(got.begin(), got.end(), -1.0);
            builds->at(level)(g, data.data(), corners.data(), n, got.data());
            CHECK(std::memcmp(got.data(), ref.data(), sizeof(double) * got.size()) == 0);
        }
    }
}

TEST_CASE("kernels: every build's factor sums give factor_sums_reference's bits", "[kernels][qemu]") {
    // Rows of 16 floats (a multiple of every build's lanes), the 12 of three groups of 4 used.
    const std::size_t width = 16, n_rows = 40;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> factor(-1.0f, 1.0f), weight(0.0f, 1.0f);
    std::vector<float> u(n_rows * width), v(n_rows * width), mix(3 * width);
    for (float& x : u) x = factor(rng);
    for (float& x : v) x = factor(rng);
    for (float& x : mix) x = factor(rng);
    k::FactorView f;
    f.width = width;
    f.u = u.data(), f.v = v.data(), f.mix = mix.data();
    // One channel's ceiling within the values' range, so the clamp is exercised.
    f.ceiling[0] = 0.05f, f.ceiling[1] = f.ceiling[2] = std::numeric_limits<float>::max();
    const std::size_t n = 3000;
    std::vector<SumsCase> cases(n);
    std::uniform_int_distribution<int> row(0, static_cast<int>(n_rows) - 1);
    for (SumsCase& c : cases)
        for (int j = 0; j < 4; ++j) c.rows[j] = row(rng), c.cols[j] = row(rng), c.rw[j] = weight(rng), c.cw[j] = weight(rng);
    std::vector<float> ref(12 * n), got(12 * n);
    const auto sums = BRDFZ_HWY_BUILDS(SumsAll);
    const auto lanes = BRDFZ_HWY_BUILDS(SumsLanes);
    const auto fused = BRDFZ_HWY_BUILDS(SumsFused);
    std::size_t clamped = 0;
    for (detail::Simd level : test::simd_levels()) {
        INFO(test::simd_label(level));
        const int w = lanes.at(level)();
        const bool fma = fused.at(level)();
        CHECK(w == static_cast<int>(k::factor_lanes(level)));
        CHECK(fma == k::factor_fused(level));
        if (w == 8)
            fma ? reference_sums<8, true>(f, cases.data(), n, ref.data()) : reference_sums<8, false>(f, cases.data(), n, ref.data());
        else
            fma ? reference_sums<4, true>(f, cases.data(), n, ref.data()) : reference_sums<4, false>(f, cases.data(), n, ref.data());
        std::fill(got.begin(), got.end(), -1.0f);
        sums.at(level)(f, cases.data(), n, got.data());
        CHECK(std::memcmp(got.data(), ref.data(), sizeof(float) * got.size()) == 0);
        for (std::size_t i = 0; i < got.size(); i += 3) clamped += got[i] == f.ceiling[0];
    }
    CHECK(clamped > 0);
}

TEST_CASE("kernels: every build's factored eval gives the reference's bits, coordinates and transform too",
          "[kernels][qemu]") {
    k::FactorView f;
    f.grid.n_theta_h = 10, f.grid.n_theta_d = 9, f.grid.n_phi_d = 12;
    f.space = runtime::layout::kSpaceLog;
    f.width = 16;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> factor(-0.5f, 1.0f);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const std::size_t n_rows = static_cast<std::size_t>(f.grid.n_theta_h) * f.grid.n_theta_d;
    const std::size_t n_cols = static_cast<std::size_t>(f.grid.n_theta_d) * f.grid.n_phi_d;
    // Rows enough for either layout's U and V.
    std::vector<float> u(std::max(n_rows, n_cols) * f.width), v(u.size()), mix(3 * f.width);
    for (float& x : u) x = factor(rng);
    for (float& x : v) x = factor(rng);
    for (float& x : mix) x = factor(rng);
    f.u = u.data(), f.v = v.data(), f.mix = mix.data();
    f.ceiling[0] = 0.3f, f.ceiling[1] = f.ceiling[2] = 4.0f;
    // Directions over the hemisphere; some pairs at the pole or mirrored (θh or θd 0: the exact fallback).
    const std::size_t n = 4000;
    std::vector<Vec3> wi(n), wo(n);
    const auto direction = [&] {
        const double z = unit(rng), r = std::sqrt(1.0 - z * z), phi = 2.0 * k::kPi * unit(rng);
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    for (std::size_t i = 0; i < n; ++i) {
        wi[i] = direction(), wo[i] = i % 50 == 0 ? wi[i] : direction();
        if (i % 50 == 1) wi[i] = wo[i] = {0.0, 0.0, 1.0};
    }
    const auto eval = BRDFZ_HWY_BUILDS(EvalAll);
    std::vector<double> ref(3 * n), got(3 * n);
    std::size_t cases = 0;
    for (int layout : {runtime::layout::kLayoutHxDP, runtime::layout::kLayoutHDxP})
        for (bool grouped : {false, true})
            for (detail::Simd level : test::simd_levels()) {
                INFO(test::simd_label(level) << ", layout " << layout << (grouped ? ", grouped" : ""));
                f.layout = layout, f.grouped = grouped;
                const bool fma = k::factor_fused(level);
                if (k::factor_lanes(level) == 8)
                    fma ? reference_eval<8, true>(f, wi.data(), wo.data(), n, ref.data())
                        : reference_eval<8, false>(f, wi.data(), wo.data(), n, ref.data());
                else
                    fma ? reference_eval<4, true>(f, wi.data(), wo.data(), n, ref.data())
                        : reference_eval<4, false>(f, wi.data(), wo.data(), n, ref.data());
                std::fill(got.begin(), got.end(), -1.0);
                eval.at(level)(f, wi.data(), wo.data(), n, got.data());
                CHECK(std::memcmp(got.data(), ref.data(), sizeof(double) * got.size()) == 0);
                CHECK(std::all_of(got.begin(), got.end(), [](double x) { return std::isfinite(x) && x >= 0.0; }));
                ++cases;
            }
    CHECK(cases == 4 * test::simd_levels().size());
}

TEST_CASE("kernels: the baseline level runs its scalar form where SSE4.2 is missing or turned off", "[kernels]") {
    const auto lanes = BRDFZ_HWY_BUILDS(SumsLanes);
    REQUIRE(lanes.fallback != nullptr);
    if (!runtime::kernels::cpu_has_sse4()) {
        CHECK(lanes.at(detail::Simd::Sse2) == lanes.fallback);
        return;
    }
    CHECK(lanes.at(detail::Simd::Sse2) == lanes.sse4);
    runtime::kernels::baseline_sse4 = false;
    const auto scalar = lanes.at(detail::Simd::Sse2);
    runtime::kernels::baseline_sse4 = true;
    CHECK(scalar == lanes.fallback);
    CHECK(scalar != lanes.sse4);
}
#endif  // HWY_ONCE
