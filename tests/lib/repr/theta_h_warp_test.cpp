// The θh axis warped by a specular peak (GridSpec::theta_h_warp, spec key hwarp): its maps, the kinds
// that take it, hwarp=auto's estimate of a peak, the container and the runtime layout.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "brdfz/compress.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/runtime_layout.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/runtime/runtime.h"
#include "detail/table_lookup.h"
#include "repr/kinds/common.h"
#include "test_util.h"

using namespace brdfz;

namespace {

constexpr double kDeg = M_PI / 180.0;

// f = (0.1 + u/n)·(1, 0.5, 0.25), u/n the coordinate of the θh axis warped by s: linear in it, so a table
// on that axis interpolates it exactly.
class LinearInWarpedThetaH final : public Brdf {
public:
    explicit LinearInWarpedThetaH(double s) : s_(s) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "linear in the warped theta_h coordinate"; }
    double coordinate(const Vec3& wi, const Vec3& wo) const { return axis::theta_h_to_u(to_half_diff(wi, wo).theta_h, 1, s_); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override {
        const double v = 0.1 + coordinate(wi, wo);
        return {v, 0.5 * v, 0.25 * v};
    }

private:
    double s_;
};

// A diffuse base and, unless `height` is 0, a peak about the half vector falling to half its height at
// θh = `half_width` (whatever θd): base + height·2^(−(θh/half_width)²).
class Peak final : public Brdf {
public:
    Peak(double height, double half_width) : height_(height), width_(half_width) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "a Gaussian peak about the half vector"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override {
        const double t = to_half_diff(wi, wo).theta_h / width_;
        const double v = 0.2 + height_ * std::exp2(-t * t);
        return {v, 0.8 * v, 0.6 * v};
    }

private:
    double height_, width_;
};

const GridSpec& grid_of(const Brdf& b) {
    if (const auto* t = dynamic_cast<const TabularBrdf*>(&b)) return t->table().grid();
    if (const auto* c = dynamic_cast<const CompactTableBrdf*>(&b)) return c->table().grid();
    return dynamic_cast<const FactoredBrdf&>(b).factors().grid;
}

}  // namespace

TEST_CASE("the warped θh axis: its inverse, its slope, and the fast coordinates", "[warp][qemu]") {
    for (const double s : {0.01 * kDeg, 0.5 * kDeg, 7.0 * kDeg, 45.0 * kDeg})
        for (const int n : {8, 90, 4096}) {
            INFO("s " << s << " n " << n);
            CHECK(axis::theta_h_to_u(0.0, n, s) == 0.0);
            CHECK(axis::theta_h_to_u(M_PI / 2, n, s) == Approx(n).epsilon(1e-14));
            double last = -1.0;
            for (int k = 0; k <= 64; ++k) {
                const double u = n * k / 64.0, theta = axis::u_to_theta_h(u, n, s);
                CHECK(theta > last);
                last = theta;
                CHECK(axis::theta_h_to_u(theta, n, s) == Approx(u).margin(1e-12 * n));
                // The slope, in units of π/n², against a central difference of the inverse.
                if (k > 0 && k < 64) {
                    const double du = 1e-5 * n;
                    const double numeric = (axis::u_to_theta_h(u + du, n, s) - axis::u_to_theta_h(u - du, n, s)) / (2 * du);
                    CHECK(axis::theta_h_slope(u, n, s) * M_PI / (double(n) * n) == Approx(numeric).epsilon(1e-6));
                }
            }
        }
    CHECK(axis::theta_h_slope(3.5, 16, 0.0) == 3.5);  // the square-root axis: dθh/du = π u / n²
    CHECK(axis::theta_h_density(3.5, 16, 0.0) == 1.0);
    // At the pole the warped axis has about n/s bins per radian, the square-root one infinitely many.
    CHECK(axis::theta_h_to_u(1e-6, 90, 0.5 * kDeg) / 1e-6 == Approx(90 / (0.5 * kDeg)).epsilon(0.01));

    // The vectorised coordinates agree with the exact ones on a warped grid, as on the others.
    GridSpec g{64, 32, 64, BinPosition::Centre, 0.6, Symmetry::Bilateral, 1.5 * kDeg};
    std::mt19937_64 rng(3);
    std::normal_distribution<double> normal;
    int checked = 0;
    for (int k = 0; k < 20000; ++k) {
        const Vec3 wi = normalize({normal(rng), normal(rng), std::fabs(normal(rng))});
        // Half of the pairs near the mirror direction, where the warped bins are narrow.
        const Vec3 mirror{-wi.x, -wi.y, wi.z};
        const Vec3 wo = k % 2 ? normalize(Vec3{normal(rng), normal(rng), std::fabs(normal(rng))})
                              : normalize(mirror + 0.02 * Vec3{normal(rng), normal(rng), normal(rng)});
        if (!(wo.z > 0.0)) continue;
        const detail::BinCoords exact = detail::bin_coords(g, wi, wo), fast = detail::fast_bin_coords(g, wi, wo);
        if (fast.up > 1e299) continue;  // ill-conditioned φd: the callers take bin_coords there
        CHECK(fast.uh == Approx(exact.uh).margin(1e-7));
        CHECK(fast.ud == Approx(exact.ud).margin(1e-7));
        ++checked;
    }
    CHECK(checked > 9000);
}

TEST_CASE("tables and factors on a warped θh axis: exact for data linear in its coordinate, options checked",
          "[warp]") {
    const double s = 2.0 * kDeg;
    const LinearInWarpedThetaH source(s);
    const Compressed warped = compress(source, "tabular:res=16x4x4,hwarp=2");
    const Compressed plain = compress(source, "tabular:res=16x4x4");
    CHECK(warped.spec == "tabular:res=16x4x4,hwarp=2");
    CHECK(grid_of(*warped.brdf).theta_h_warp == Approx(s).epsilon(1e-15));
    CHECK(warped.brdf->nbytes() == plain.brdf->nbytes());  // the warp is one attribute, not stored per bin
    CHECK_THAT(warped.brdf->describe(), Catch::Contains("theta_h warp 2 deg"));
    // Pairs whose θh lies between the first and last θh samples (beyond them the lookup is constant).
    const GridSpec& g = grid_of(*warped.brdf);
    const double lo = g.theta_h_at(0), hi = g.theta_h_at(15);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<Vec3> wi, wo;
    while (wi.size() < 10000) {
        const auto [a, b] = from_half_diff({lo + (hi - lo) * u01(rng), 2 * M_PI * u01(rng), 0.3 * u01(rng), 2 * M_PI * u01(rng)});
        if (!(a.z > 0 && b.z > 0)) continue;
        wi.push_back(a);
        wo.push_back(b);
    }
    std::vector<Rgb> fw(wi.size()), fp(wi.size());
    warped.brdf->eval(wi, wo, fw);
    plain.brdf->eval(wi, wo, fp);
    double worst_warped = 0.0, worst_plain = 0.0;
    for (std::size_t k = 0; k < wi.size(); ++k) {
        const Rgb f = source.eval(wi[k], wo[k]);
        for (int c = 0; c < 3; ++c) {
            worst_warped = std::max(worst_warped, std::fabs(fw[k][c] / f[c] - 1.0));
            worst_plain = std::max(worst_plain, std::fabs(fp[k][c] / f[c] - 1.0));
        }
    }
    CHECK(worst_warped < 1e-6);  // float32 values
    CHECK(worst_plain > 1e-2);   // the square-root axis interpolates another curve

    // A rank-1 function of the warped coordinate: the factorisations hold it as exactly.
    const Compressed svd = compress(source, "svd:rank=1,space=linear,res=16x4x8,hwarp=2");
    std::vector<Rgb> fs(wi.size());
    svd.brdf->eval(wi, wo, fs);
    double worst_svd = 0.0;
    for (std::size_t k = 0; k < wi.size(); ++k) worst_svd = std::max(worst_svd, std::fabs(fs[k][0] / source.eval(wi[k], wo[k])[0] - 1.0));
    CHECK(worst_svd < 1e-5);
    CHECK_THAT(svd.brdf->describe(), Catch::Contains("theta_h warp 2 deg"));

    // Compact types, bivariate tables and nmf take the warp too.
    for (const char* spec : {"tabular:res=8x8x8,dtype=u8log,filter=lsq,hwarp=0.5", "bivariate:res=8x8,dtype=f16,hwarp=10",
                             "nmf:rank=2,res=8x8x8,iterations=5,hwarp=45", "svd:rank=2,res=8x8x8,fit=lsq,weight=solid,hwarp=3"}) {
        INFO(spec);
        CHECK(grid_of(*compress(source, spec).brdf).theta_h_warp > 0.0);
    }
    CHECK_THROWS_WITH(compress(source, "tabular:res=8x8x8,hwarp=50"), Catch::Contains("hwarp=50 must be 0, auto or in [0.01, 45]"));
    CHECK_THROWS_WITH(compress(source, "tabular:res=8x8x8,hwarp=0.001"), Catch::Contains("hwarp=0.001 must be"));
    CHECK_THROWS_WITH(compress(source, "tabular:res=8x8x8,hwarp=-1"), Catch::Contains("hwarp=-1 must be"));
    CHECK_THROWS_WITH(compress(source, "tabular:res=8x8x8,hwarp=x"), Catch::Contains("not a finite number"));
    CHECK_THROWS_WITH(compress(*plain.brdf, "svd:rank=2,hwarp=2"), Catch::Contains("hwarp= applies to the res= grid"));
    CHECK_THROWS_AS(compress(source, "pca:hwarp=2"), ValueError);
    GridSpec bad{8, 8, 8};
    bad.theta_h_warp = 1.0;  // 57°
    CHECK_THROWS_WITH(bad.validate(), Catch::Contains("theta_h warp"));
}

TEST_CASE("hwarp=auto: the source's own peak sets the warp, a matte source keeps the square-root axis", "[warp]") {
    for (const double width : {0.4, 2.0}) {
        INFO("half width " << width << " deg");
        const Peak peak(200.0, width * kDeg);
        CHECK(kinds::specular_peak_half_width(peak) / kDeg == Approx(width).epsilon(0.06));
        const Compressed c = compress(peak, "tabular:res=32x16x8,hwarp=auto");
        CHECK(grid_of(*c.brdf).theta_h_warp == Approx(3.0 * kinds::specular_peak_half_width(peak)).epsilon(1e-12));
        CHECK_THAT(c.notes.front(), Catch::Contains("hwarp=auto: the specular peak's half width"));
        // Judged over directions, as a renderer sees it, the warped table of the same size is closer.
        MetricOptions m;
        m.over = Over::Directions;
        m.directions = 1 << 16;
        const double auto_error = compare(peak, *c.brdf, m).cos_rmse_rel.mean;
        const double root_error = compare(peak, *compress(peak, "tabular:res=32x16x8").brdf, m).cos_rmse_rel.mean;
        CHECK(auto_error < 0.5 * root_error);
    }
    const Peak matte(0.0, 1.0);
    CHECK(kinds::specular_peak_half_width(matte) == 0.0);
    const Compressed c = compress(matte, "tabular:res=8x8x8,hwarp=auto");
    CHECK(grid_of(*c.brdf).theta_h_warp == 0.0);
    CHECK_THAT(c.notes.front(), Catch::Contains("no specular peak"));
}

TEST_CASE("a warped θh axis round-trips through .brdfz and the runtime layout", "[warp][container][runtime][qemu]") {
    test::TempDir dir;
    const Peak peak(50.0, 1.0 * kDeg);
    for (const char* spec : {"tabular:res=16x8x8,hwarp=auto", "tabular:res=16x8x8,dtype=f16,symmetry=bilateral,hwarp=3",
                             "svd:rank=2,space=cos,res=16x8x8,dtype=f16,hwarp=auto"}) {
        INFO(spec);
        const Compressed c = compress(peak, spec);
        const std::string path = (dir.path / "w.brdfz").string();
        container::write(path, *c.brdf);
        const container::ReadResult r = container::read(path);
        CHECK(grid_of(*r.brdf).theta_h_warp == grid_of(*c.brdf).theta_h_warp);
        CHECK(r.meta.min_reader_version == 7);
        const bool factored = dynamic_cast<const FactoredBrdf*>(c.brdf.get()) != nullptr;
        const container::Feature feature{factored ? "factored.warped-theta-h" : "tabular.warped-theta-h", 7};
        CHECK(std::find(r.meta.features.begin(), r.meta.features.end(), feature) != r.meta.features.end());

        const std::vector<unsigned char> layout = runtime_layout::encode(*c.brdf);
        CHECK(layout[8] == 2);  // the layout version that has HWRP
        const runtime::Material m = runtime::Material::from_memory(layout.data(), layout.size(), true);
        REQUIRE(m);
        std::mt19937_64 rng(9);
        std::normal_distribution<double> normal;
        for (int k = 0; k < 2000; ++k) {
            const Vec3 wi = normalize({normal(rng), normal(rng), std::fabs(normal(rng)) + 0.1});
            const Vec3 wo = normalize(Vec3{-wi.x, -wi.y, wi.z} + 0.03 * Vec3{normal(rng), normal(rng), normal(rng)});
            if (!(wo.z > 0.0)) continue;
            const Rgb a = r.brdf->eval(wi, wo), b = c.brdf->eval(wi, wo);
            const runtime::Rgb64 x = m.eval(wi, wo);
            for (int ch = 0; ch < 3; ++ch) {
                CHECK(a[ch] == b[ch]);
                CHECK(x[ch] == Approx(b[ch]).epsilon(1e-5).margin(1e-9));
            }
        }
        // The same bytes under a version-1 header are refused, not read on the square-root axis.
        std::vector<unsigned char> v1 = layout;
        v1[8] = 1;
        std::string error;
        CHECK(!runtime::Material::from_memory(v1.data(), v1.size(), true, &error));
        CHECK_THAT(error, Catch::Contains("HWRP"));
    }
    // A layout without a warped axis stays version 1, which every runtime reads.
    CHECK(runtime_layout::encode(*compress(peak, "tabular:res=8x8x8").brdf)[8] == 1);
}

TEST_CASE("hwarp=auto holds chm_mint's half-degree peak: a table of the same bytes much closer", "[warp][rgl]") {
    const std::filesystem::path path = std::filesystem::path(BRDFZ_SHARED_DIR) / "data" / "rgl" / "chm_mint_rgb.bsdf";
    if (!std::filesystem::exists(path)) {
        WARN("skipped: " << path << " is missing (../shared/data)");
        return;
    }
    const Loaded loaded = load(path.string());
    const Brdf* source = loaded.brdf.get();
    MetricOptions m;
    m.over = Over::Directions;
    m.directions = 1 << 17;
    const double root = compare(*source, *compress(*source, "tabular:res=64x45x45,symmetry=bilateral,dtype=f16").brdf, m).cos_rmse_rel.mean;
    const Compressed warped = compress(*source, "tabular:res=64x45x45,symmetry=bilateral,dtype=f16,hwarp=auto");
    const double auto_error = compare(*source, *warped.brdf, m).cos_rmse_rel.mean;
    INFO(warped.notes.front() << ": " << auto_error << " against " << root);
    CHECK(grid_of(*warped.brdf).theta_h_warp / kDeg == Approx(3 * 0.45).epsilon(0.1));
    CHECK(auto_error < 0.65 * root);
}
