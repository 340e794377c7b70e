// RglBrdf's batch kernels (formats/rgl/kernels.cpp) against the scalar warps they replace, written out
// below as they were (libm's asin, atan2, sin and cos; std::lower_bound; one pair at a time), and
// against themselves: one call = batch, in every SIMD build, and the builds alike.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/formats/rgl.h"
#include "rgl/marginal2d.h"
#include "sample_stats.h"
#include "simd_levels.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

// The kernels' angles come from a polynomial arctangent (6e-11 relative) and a sine table (a few ulp)
// where the scalar path called libm: what they may change in f, pdf and the weights (relative, with the
// floors of check_against_scalar) and in a sampled direction (rgl.h). On the shared files the worst seen
// is a third of these.
constexpr double kRel = 1e-8, kDir = 1e-8;

// ---- The scalar path: Mitsuba's `measured` in double, one pair at a time, libm's functions. ----
namespace ref {

constexpr double kPi = std::numbers::pi;

double clamp01(double v) { return std::fmin(std::fmax(v, 0.0), 1.0); }
double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }

struct Weights {
    std::size_t lower = 0, step = 0;
    double w_upper = 0.0;
};
Weights slice_weights(std::span<const float> values, double x) {
    if (values.size() < 2) return {};
    const auto it = std::lower_bound(values.begin() + 1, values.end() - 1, x, [](float v, double t) { return v < t; });
    const auto lower = static_cast<std::size_t>(it - values.begin()) - 1;
    const double p0 = values[lower], p1 = values[lower + 1];
    return {lower, 1, clamp01((x - p0) / (p1 - p0))};
}

// Two slices of a stack of tables blended entry by entry: slices `stride` floats apart (slice-major
// tensors), or entries `entry` floats apart with the slices innermost (the warps' tables, kernels.h).
struct Blend {
    const float* lower;
    const float* upper;
    std::size_t entry;
    double w_lower, w_upper;
    double operator[](std::size_t i) const { return w_lower * lower[i * entry] + w_upper * upper[i * entry]; }
};
Blend blend(const float* first, std::size_t stride, const Weights& w) {
    return {first + w.lower * stride, first + (w.lower + w.step) * stride, 1, 1.0 - w.w_upper, w.w_upper};
}
Blend blend_innermost(const float* first, std::size_t entry, const Weights& w) {
    return {first + w.lower, first + w.lower + w.step, entry, 1.0 - w.w_upper, w.w_upper};
}

struct Patch {
    std::size_t ix, iy;
    double fx, fy;
};
Patch locate(double x, double y, std::size_t rows, std::size_t cols) {
    const double sx = clamp01(x) * static_cast<double>(cols - 1), sy = clamp01(y) * static_cast<double>(rows - 1);
    const std::size_t ix = std::min(static_cast<std::size_t>(sx), cols - 2);
    const std::size_t iy = std::min(static_cast<std::size_t>(sy), rows - 2);
    return {ix, iy, sx - static_cast<double>(ix), sy - static_cast<double>(iy)};
}
double bilinear(const Blend& t, std::size_t rows, std::size_t cols, double x, double y) {
    const Patch q = locate(x, y, rows, cols);
    const std::size_t i = q.iy * cols + q.ix;
    return lerp(lerp(t[i], t[i + 1], q.fx), lerp(t[i + cols], t[i + cols + 1], q.fx), q.fy);
}
double partial_integral(double t, double width, double v0, double v1) { return t * lerp(v0, v1, 0.5 * t) * width; }
double invert_partial_integral(double s, double v0, double v1) {
    const double denom = v0 + std::sqrt(std::fmax(v0 * v0 + 2.0 * s * (v1 - v0), 0.0));
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;
}
template <typename Cdf>
std::size_t find_cell(std::size_t n, const Cdf& cdf, double u) {
    std::size_t first = 1, count = n - 1;
    while (count > 0) {
        const std::size_t half = count / 2;
        if (cdf(first + half) < u) {
            first += half + 1;
            count -= half + 1;
        } else {
            count = half;
        }
    }
    return first - 1;
}

struct Warped {
    double x, y, pdf;
};

struct Warp {
    rgl::detail::WarpTables t;
    std::size_t R() const { return static_cast<std::size_t>(t.rows); }
    std::size_t C() const { return static_cast<std::size_t>(t.cols); }

    Warped sample(double ux, double uy, const Weights& w) const {
        const std::size_t rows = R(), cols = C(), n_cond = cols - 1;
        const std::size_t S = static_cast<std::size_t>(t.stride);
        const Blend data = blend_innermost(t.data, S, w), cond = blend_innermost(t.cond, S, w),
                    marg = blend_innermost(t.marg, S, w);
        const double width = 1.0 / static_cast<double>(cols - 1), height = 1.0 / static_cast<double>(rows - 1);
        ux = clamp01(ux), uy = clamp01(uy);
        const auto marg_at = [&](std::size_t j) { return j == 0 ? 0.0 : marg[j - 1]; };
        const std::size_t iy = find_cell(rows - 1, marg_at, uy);
        const std::size_t row0 = iy * n_cond, row1 = row0 + n_cond;
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        const double fy = invert_partial_integral((uy - marg_at(iy)) / height, r0, r1);
        const double target = ux * lerp(r0, r1, fy);
        const auto cond_at = [&](std::size_t j) {
            return j == 0 ? 0.0 : lerp(cond[row0 + j - 1], cond[row1 + j - 1], fy);
        };
        const std::size_t ix = find_cell(cols - 1, cond_at, target);
        const std::size_t i = iy * cols + ix;
        const double c0 = lerp(data[i], data[i + cols], fy), c1 = lerp(data[i + 1], data[i + cols + 1], fy);
        const double fx = invert_partial_integral((target - cond_at(ix)) / width, c0, c1);
        return {(static_cast<double>(ix) + fx) * width, (static_cast<double>(iy) + fy) * height, lerp(c0, c1, fx)};
    }

    Warped invert(double px, double py, const Weights& w) const {
        const std::size_t rows = R(), cols = C(), n_cond = cols - 1;
        const std::size_t S = static_cast<std::size_t>(t.stride);
        const Blend data = blend_innermost(t.data, S, w), cond = blend_innermost(t.cond, S, w),
                    marg = blend_innermost(t.marg, S, w);
        const Patch q = locate(px, py, rows, cols);
        const std::size_t i = q.iy * cols + q.ix;
        const double c0 = lerp(data[i], data[i + cols], q.fy), c1 = lerp(data[i + 1], data[i + cols + 1], q.fy);
        const std::size_t row0 = q.iy * n_cond, row1 = row0 + n_cond;
        double x = partial_integral(q.fx, 1.0 / static_cast<double>(cols - 1), c0, c1);
        if (q.ix > 0) x += lerp(cond[row0 + q.ix - 1], cond[row1 + q.ix - 1], q.fy);
        const double r0 = cond[row0 + n_cond - 1], r1 = cond[row1 + n_cond - 1];
        x /= lerp(r0, r1, q.fy);
        double y = partial_integral(q.fy, 1.0 / static_cast<double>(rows - 1), r0, r1);
        if (q.iy > 0) y += marg[q.iy - 1];
        return {x, y, lerp(c0, c1, q.fx)};
    }

    double density(double px, double py, const Weights& w) const {
        return bilinear(blend_innermost(t.data, static_cast<std::size_t>(t.stride), w), R(), C(), px, py);
    }
};

double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / kPi)); }
double u_of_phi(double phi) { return (phi + kPi) * (0.5 / kPi); }
bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

struct Microfacet {
    Vec3 m;
    double theta, ux, uy;
};
Microfacet microfacet(const Vec3& w, const Vec3& other) {
    const Vec3 m = normalize(w + other);
    const double theta = elevation(m);
    double u_phi = u_of_phi(std::atan2(m.y, m.x) - std::atan2(w.y, w.x));
    u_phi -= std::floor(u_phi);
    return {m, theta, u_of_theta(theta), u_phi};
}
double solid_angle_per_unit_square(double u_theta, double theta_m, double w_dot_m) {
    return std::fmax(2.0 * kPi * kPi * u_theta * std::sin(theta_m) * 4.0 * w_dot_m, 0.0);
}

// The reader's tables rebuilt from the RglBrdf's tensors, read as the scalar path read them.
class Model {
public:
    explicit Model(const rgl::RglBrdf& b)
        : t_(b.tensors()),
          vndf_("vndf", t_.vndf.values, t_.vndf.slices, t_.vndf.rows, t_.vndf.cols),
          lum_(t_.luminance.values.empty()
                   ? nullptr
                   : std::make_unique<rgl::detail::Marginal2D>("luminance", t_.luminance.values, t_.luminance.slices,
                                                               t_.luminance.rows, t_.luminance.cols)) {}

    Rgb eval(const Vec3& wi, const Vec3& wo) const {
        if (!(wi.z > 0 && wo.z > 0) || !finite(wi) || !finite(wo)) return {0, 0, 0};
        const double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
        const Microfacet mf = microfacet(wi, wo);
        const Weights w = slice_weights(t_.theta_i, theta_i);
        const Warped s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
        double scale = 1.0 / wo.z;
        if (t_.jacobian) {
            const Weights one{};
            const double d = bilinear(blend(t_.ndf.values.data(), 0, one), t_.ndf.rows, t_.ndf.cols, mf.ux, mf.uy);
            const double sigma = bilinear(blend(t_.sigma.values.data(), 0, one), t_.sigma.rows, t_.sigma.cols,
                                          u_of_theta(theta_i), u_of_phi(phi_i));
            scale *= d / (4.0 * sigma);
        }
        const std::size_t plane = t_.rgb.rows * t_.rgb.cols;
        Rgb f;
        for (std::size_t c = 0; c < 3; ++c) {
            const double v = bilinear(blend(t_.rgb.values.data() + c * plane, 3 * plane, w), t_.rgb.rows, t_.rgb.cols,
                                      s.x, s.y) *
                             scale;
            f[c] = std::isfinite(v) ? v : 0.0;
        }
        return f;
    }

    double pdf(const Vec3& wo, const Vec3& wi) const {
        if (!(wo.z > 0 && wi.z > 0) || !finite(wo) || !finite(wi)) return 0;
        const Weights w = slice_weights(t_.theta_i, elevation(wo));
        const Microfacet mf = microfacet(wo, wi);
        const Warped s = Warp{vndf_.tables()}.invert(mf.ux, mf.uy, w);
        const double jacobian = solid_angle_per_unit_square(mf.ux, mf.theta, dot(wo, mf.m));
        if (!(s.pdf > 0.0 && jacobian > 0.0)) return 0.0;
        const double pdf = s.pdf * (lum_ ? Warp{lum_->tables()}.density(s.x, s.y, w) : 1.0) / jacobian;
        return std::isfinite(pdf) ? pdf : 0.0;
    }

    BrdfSample sample(const Vec3& wo, double u1, double u2) const {
        if (!Brdf::can_draw(wo, u1, u2) || !finite(wo)) return {};
        const Weights w = slice_weights(t_.theta_i, elevation(wo));
        Warped s{u2, u1, 1.0};
        if (lum_) s = Warp{lum_->tables()}.sample(s.x, s.y, w);
        const Warped u_m = Warp{vndf_.tables()}.sample(s.x, s.y, w);
        const double theta_m = u_m.x * u_m.x * (kPi / 2.0);
        const Vec3 m = spherical_direction(theta_m, (2.0 * u_m.y - 1.0) * kPi + std::atan2(wo.y, wo.x));
        const double wo_dot_m = dot(wo, m);
        const double jacobian = solid_angle_per_unit_square(u_m.x, theta_m, wo_dot_m);
        const double pdf = jacobian > 0.0 ? s.pdf * u_m.pdf / jacobian : 0.0;
        BrdfSample out{(2.0 * wo_dot_m) * m - wo, pdf, {}};
        if (!Brdf::usable(out)) return {};
        const Rgb f = eval(out.wi, wo);
        for (int c = 0; c < 3; ++c) out.weight[c] = f[c] * out.wi.z / out.pdf;
        return out;
    }

private:
    rgl::Tensors t_;
    rgl::detail::Marginal2D vndf_;
    std::unique_ptr<rgl::detail::Marginal2D> lum_;
};

}  // namespace ref

std::vector<fs::path> rgl_files() {
    std::vector<fs::path> files;
    const fs::path dir = fs::path(BRDFZ_SHARED_DIR) / "data" / "rgl";
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return files;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".bsdf") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

// Pairs uniform on the upper hemisphere, then the awkward ones: at the pole, along the axes (azimuth
// ±π, signed zeros), grazing, and wi = wo.
struct Inputs {
    std::vector<Vec3> wi, wo;
    std::vector<std::array<double, 2>> u;
};
Inputs inputs(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const auto upper = [&] {
        const double z = u01(rng), r = std::sqrt(1 - z * z), phi = 2 * std::numbers::pi * u01(rng);
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    Inputs in;
    for (std::size_t k = 0; k < n; ++k) {
        in.wi.push_back(upper());
        in.wo.push_back(upper());
        in.u.push_back({u01(rng), u01(rng)});
    }
    const std::vector<Vec3> special = {{0, 0, 1},          {-0.0, 0, 1},          {0, -0.0, 1},       {-0.0, -0.0, 1},
                                       {-0.6, 0, 0.8},     {-0.6, -0.0, 0.8},     {0.6, 0, 0.8},      {0, 0.6, 0.8},
                                       {0.9999, 0, 0.01414}, {0, -1, 1e-9},      {1e-9, 1e-9, 1},    {-0.8, 0.6, 1e-300}};
    for (const Vec3& a : special)
        for (const Vec3& b : special) {
            in.wi.push_back(normalize(a));
            in.wo.push_back(normalize(b));
            in.u.push_back({u01(rng), u01(rng)});
        }
    return in;
}

using test::same_bits;

// The batch kernels against the scalar path on n random pairs and the awkward ones.
void check_against_scalar(const rgl::RglBrdf& b, std::size_t n) {
    const ref::Model model(b);
    const Inputs in = inputs(n, 20261201);
    const std::size_t m = in.wi.size();
    std::vector<Rgb> f(m);
    std::vector<double> p(m);
    std::vector<BrdfSample> s(m);
    b.eval(in.wi, in.wo, f);
    b.pdf(in.wo, in.wi, p);
    b.sample(in.wo, in.u, s);
    // f relative to the pair's largest channel, or to 1e-4 of the batch's largest value where that is
    // larger: values near 0 come from blends of larger ones (of both signs, in real files), whose
    // rounding they inherit. Densities and weights likewise, relative to their own value or to 1e-4 of
    // the batch's largest density.
    std::vector<Rgb> g(m);
    std::vector<double> q(m);
    std::vector<BrdfSample> t(m);
    double f_top = 0, p_top = 0;
    for (std::size_t k = 0; k < m; ++k) {
        g[k] = model.eval(in.wi[k], in.wo[k]);
        q[k] = model.pdf(in.wo[k], in.wi[k]);
        t[k] = model.sample(in.wo[k], in.u[k][0], in.u[k][1]);
        for (double v : g[k]) f_top = std::max(f_top, std::fabs(v));
        p_top = std::max({p_top, q[k], t[k].pdf});
    }
    const auto rel = [](double a, double b, double floor) { return std::fabs(a - b) / std::max(std::fabs(b), floor); };
    double worst_f = 0, worst_p = 0, worst_w = 0, worst_dir = 0;
    std::size_t mismatched = 0;  // a draw that failed in one and not in the other
    for (std::size_t k = 0; k < m; ++k) {
        const double scale = std::max({std::fabs(g[k][0]), std::fabs(g[k][1]), std::fabs(g[k][2]), 1e-4 * f_top});
        for (int c = 0; c < 3; ++c) worst_f = std::max(worst_f, scale > 0 ? std::fabs(f[k][c] - g[k][c]) / scale : 0.0);
        worst_p = std::max(worst_p, rel(p[k], q[k], 1e-4 * p_top));
        mismatched += (s[k].pdf > 0) != (t[k].pdf > 0);
        if (s[k].pdf > 0 && t[k].pdf > 0) {
            worst_dir = std::max(worst_dir, length(s[k].wi - t[k].wi));
            worst_p = std::max(worst_p, rel(s[k].pdf, t[k].pdf, 1e-4 * p_top));
            // The weight f·cosθi/pdf, its f floored as above.
            const double w = std::max({std::fabs(t[k].weight[0]), std::fabs(t[k].weight[1]), std::fabs(t[k].weight[2]),
                                       1e-4 * f_top * t[k].wi.z / t[k].pdf});
            for (int c = 0; c < 3; ++c)
                worst_w = std::max(worst_w, w > 0 ? std::fabs(s[k].weight[c] - t[k].weight[c]) / w : 0.0);
        }
    }
    INFO("worst: f " << worst_f << ", pdf " << worst_p << ", weight " << worst_w << ", direction " << worst_dir);
    CHECK(worst_f <= kRel);
    CHECK(worst_p <= kRel);
    CHECK(worst_w <= kRel);
    CHECK(worst_dir <= kDir);
    CHECK(mismatched == 0);
}

}  // namespace

namespace {

// Tensors of random positive tables on small grids (rows ≠ cols) at `n_theta` elevations.
rgl::Tensors random_tensors(int n_theta, std::uint64_t seed, bool luminance) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> u(0.05f, 1.0f);
    const auto grids = [&](std::size_t slices, std::size_t rows, std::size_t cols) {
        rgl::Grids g{slices, rows, cols, std::vector<float>(slices * rows * cols)};
        for (float& v : g.values) v = u(rng);
        return g;
    };
    rgl::Tensors t;
    for (int k = 0; k < n_theta; ++k) t.theta_i.push_back(static_cast<float>(1.5 * (k + 0.3) / n_theta));
    const auto slices = static_cast<std::size_t>(n_theta);
    t.ndf = grids(1, 3, 9);
    t.sigma = grids(1, 2, 7);
    t.vndf = grids(slices, 11, 13);
    t.rgb = grids(3 * slices, 5, 6);
    if (luminance) t.luminance = grids(slices, 5, 6);
    return t;
}

void check_random_tensors(std::size_t n) {
    for (const auto& [n_theta, lum] : {std::pair{1, true}, std::pair{3, true}, std::pair{4, false}}) {
        INFO(n_theta << " slices" << (lum ? "" : ", no luminance"));
        const rgl::RglBrdf b(random_tensors(n_theta, 17 + n_theta, lum));
        check_against_scalar(b, n);
    }
}

}  // namespace

TEST_CASE("rgl kernels: eval, pdf and sample within 1e-8 of the scalar path", "[rgl][kernels][light][qemu]") {
    check_random_tensors(20000);
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    for (std::size_t i = 0; i < files.size(); i += 5) check_against_scalar(*rgl::read(files[i].string()).brdf, 20000);
}

TEST_CASE("rgl kernels: eval, pdf and sample within 1e-8 of the scalar path on every shared file",
          "[rgl][kernels][heavy]") {
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped: ../shared/data/rgl missing");
        return;
    }
    for (const auto& path : files) {
        INFO(path.filename().string());
        check_against_scalar(*rgl::read(path.string()).brdf, 200000);
    }
}

namespace {

// One call at a time against the batch, and each SIMD build against the narrowest, bit for bit.
void check_builds(const rgl::RglBrdf& b, std::size_t n) {
    const Inputs in = inputs(n, 7);
    const std::size_t m = in.wi.size();
    std::vector<Rgb> f0(m), f(m);
    std::vector<double> p0(m), p(m);
    std::vector<BrdfSample> s0(m), s(m);
    bool first = true;
    for (detail::Simd level : test::simd_levels()) {
        INFO(test::simd_label(level) << " build");
        const test::SimdCap cap(level);
        b.eval(in.wi, in.wo, f);
        b.pdf(in.wo, in.wi, p);
        b.sample(in.wo, in.u, s);
        std::size_t differ = 0;
        for (std::size_t k = 0; k < m; ++k) {
            const Rgb one = b.eval(in.wi[k], in.wo[k]);
            for (int c = 0; c < 3; ++c) differ += !same_bits(one[c], f[k][c]);
            differ += !same_bits(b.pdf(in.wo[k], in.wi[k]), p[k]);
            differ += !same_bits(b.sample(in.wo[k], in.u[k][0], in.u[k][1]), s[k]);
            if (!first) {
                for (int c = 0; c < 3; ++c) differ += !same_bits(f0[k][c], f[k][c]);
                differ += !same_bits(p0[k], p[k]) + !same_bits(s0[k], s[k]);
            }
        }
        CHECK(differ == 0);
        if (first) f0 = f, p0 = p, s0 = s, first = false;
    }
}

}  // namespace

TEST_CASE("rgl kernels: one call = batch, bit for bit, and every SIMD build gives the same bits",
          "[rgl][kernels][qemu]") {
    if (test::simd_levels().size() < 2) WARN("this CPU has only the baseline build");
    for (int n_theta : {1, 3}) check_builds(rgl::RglBrdf(random_tensors(n_theta, 5, true)), 3000);
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    check_builds(*rgl::read(files.front().string()).brdf, 20000);
}

TEST_CASE("rgl kernels: the batch sampler's chi-square on random tables and a shared file, and batch = one call",
          "[rgl][kernels][sample]") {
    for (int n_theta : {1, 3}) {
        INFO(n_theta << " slices (random tables)");
        test::check_batch_sampler(rgl::RglBrdf(random_tensors(n_theta, 9, true)), 100000);
    }
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped the shared files: ../shared/data/rgl missing");
        return;
    }
    // One file: rgl_test.cpp's sampler test takes every file at more draws.
    INFO(files.front().filename().string());
    test::check_batch_sampler(*rgl::read(files.front().string()).brdf, 50000);
}

// The batch sampler's χ² on every shared file is rgl_test.cpp's sampler test (its draws are batches).
TEST_CASE("rgl kernels: batch sample, pdf and eval are one call's bits on every shared file",
          "[rgl][kernels][sample][qemu]") {
    const auto files = rgl_files();
    if (files.empty()) {
        WARN("skipped: ../shared/data/rgl missing");
        return;
    }
    for (const auto& path : files) {
        INFO(path.filename().string());
        test::check_batch_bits(*rgl::read(path.string()).brdf);
    }
}
