// Bilateral tables without a φh axis (table.h, Symmetry::Bilateral: φd over [0, π] folded by the mirror
// y → −y): the axis and its lookups, tabulation of sources with and without the mirror symmetry, every
// gridded kind that takes it, the samplers, the container and the formats that fold φd by reciprocity.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/sample/factor_sampler.h"
#include "brdfz/tabulate.h"
#include "detail/table_lookup.h"
#include "lib/grid_fixtures.h"
#include "sample_stats.h"
#include "test_util.h"

using namespace brdfz;

namespace {

// A glossy lobe times 1 + a·(cosθi − cosθo) · (1 + b·(wi × wo)_z): isotropic and, for a ≠ 0, not
// reciprocal. (wi × wo)_z changes sign under the mirror (and under the exchange), so for b ≠ 0 the source
// is not mirror-symmetric, and its mean over the mirror is the b = 0 source exactly.
class Skewed final : public Brdf {
public:
    Skewed(double a, double b, double alpha = 0.12) : a_(a), b_(b), lobe_([&] {
        CoatedDiffuseParams p;
        p.alpha = alpha;
        return p;
    }()) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 0; }
    std::string describe() const override { return "skewed coated diffuse"; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override {
        Rgb f = lobe_.eval(wi, wo);
        const double chiral = wi.x * wo.y - wi.y * wo.x;
        for (double& c : f) c *= (1.0 + a_ * (wi.z - wo.z)) * (1.0 + b_ * chiral);
        return f;
    }

private:
    double a_, b_;
    CoatedDiffuse lobe_;
};

using test::directions;
using test::FactorSampled;
using test::grid;
using test::random_upper;
using test::tabulated;

Vec3 mirrored(const Vec3& v) { return {v.x, -v.y, v.z}; }

double direction_error(const Brdf& a, const Brdf& b) { return compare(a, b, directions()).cos_rmse_rel.mean; }

}  // namespace

TEST_CASE("the bilateral φd axis: angles, coordinates, the mirror and the exchange", "[bilateral][tabular]") {
    const GridSpec g = grid(16, 16, 32, Symmetry::Bilateral);
    CHECK(g.bilateral());
    CHECK(!g.reciprocal());
    CHECK(!g.full_circle());
    CHECK(g.phi_d_range() == Approx(M_PI));
    CHECK(g.phi_d_at(31) == Approx((31.5 / 32) * M_PI));
    CHECK(g.phi_d_to_u(-M_PI / 4) == Approx(8.0));
    CHECK(g.phi_d_to_u(3 * M_PI / 4) == Approx(24.0));
    CHECK(grid(16, 16, 32, Symmetry::Reciprocal).phi_d_to_u(-M_PI / 4) == Approx(24.0));
    CHECK(parse_symmetry(symmetry_name(Symmetry::Bilateral)) == Symmetry::Bilateral);
    CHECK(std::string(symmetry_name(Symmetry::Bilateral)) == "bilateral");
    CHECK_THROWS_WITH(parse_symmetry("mirror"), Catch::Contains("'reciprocal', 'none' or 'bilateral'"));
    std::mt19937_64 rng(5);
    int checked = 0;
    for (int k = 0; k < 20000; ++k) {
        const Vec3 wi = random_upper(rng), wo = random_upper(rng);
        const detail::BinCoords exact = detail::bin_coords(g, wi, wo), fast = detail::fast_bin_coords(g, wi, wo);
        if (fast.up > g.n_phi_d) continue;  // ill-conditioned φd: callers fall back to bin_coords
        ++checked;
        REQUIRE(std::fabs(exact.up - fast.up) < 1e-6);
        REQUIRE(std::fabs(exact.ud - fast.ud) < 1e-6);
        // The mirror image has the same coordinates, to the bit in the fast ones.
        const detail::BinCoords image = detail::fast_bin_coords(g, mirrored(wi), mirrored(wo));
        REQUIRE(std::memcmp(&image, &fast, sizeof fast) == 0);
        // Exchanging wi and wo takes φd to π − φd on the folded axis.
        const detail::BinCoords swapped = detail::bin_coords(g, wo, wi);
        REQUIRE(swapped.up == Approx(g.n_phi_d - exact.up).margin(1e-6));
    }
    CHECK(checked > 19000);
}

TEST_CASE("bilateral lookups are continuous across φd = 0 and φd = π and mirror-symmetric", "[bilateral][tabular]") {
    // Random values, so that continuity comes from the lookup, not from a smooth source.
    for (BinPosition position : {BinPosition::Centre, BinPosition::Start}) {
        GridSpec g = grid(8, 8, 12, Symmetry::Bilateral);
        g.position = position;
        Table t(g);
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> u(0.1, 2.0);
        for (std::size_t b = 0; b < t.bins(); ++b) t.set(b, {u(rng), u(rng), u(rng)});
        const TabularBrdf table(std::move(t));
        CHECK(table.bilateral());
        CHECK(!table.reciprocal());
        CHECK(table.describe().find("symmetry bilateral") != std::string::npos);
        for (double theta_h : {0.2, 0.5})
            for (double theta_d : {0.3, 0.7}) {
                INFO("θh " << theta_h << ", θd " << theta_d);
                const auto at = [&](double phi_d) {
                    const auto [wi, wo] = from_half_diff({theta_h, 0.0, theta_d, phi_d});
                    return table.eval(wi, wo);
                };
                for (double end : {0.0, M_PI}) {
                    const Rgb below = at(end - 1e-7), above = at(end + 1e-7), on = at(end);
                    for (int c = 0; c < 3; ++c) {
                        CHECK(below[c] == Approx(on[c]).epsilon(1e-6));
                        CHECK(above[c] == Approx(on[c]).epsilon(1e-6));
                    }
                }
                // Elsewhere the lookup does vary with φd (the check above is not of a constant).
                CHECK(std::fabs(at(0.0)[0] - at(M_PI / 2)[0]) > 1e-3);
            }
        std::mt19937_64 pairs(8);
        for (int k = 0; k < 2000; ++k) {
            const Vec3 wi = random_upper(pairs), wo = random_upper(pairs);
            const Rgb f = table.eval(wi, wo), m = table.eval(mirrored(wi), mirrored(wo));
            for (int c = 0; c < 3; ++c) REQUIRE(m[c] == Approx(f[c]).epsilon(1e-12));
        }
    }
}

TEST_CASE("tabulation: a bilateral grid stores the mirror mean, not the reciprocal one", "[bilateral][tabulate]") {
    const Skewed chiral(0.8, 0.9), plain(0.8, 0.0);
    const GridSpec g = grid(12, 12, 24, Symmetry::Bilateral);
    const Table of_chiral = tabulated(chiral, g), of_plain = tabulated(plain, g);
    std::size_t valid = 0;
    for (std::size_t b = 0; b < of_chiral.bins(); ++b) {
        REQUIRE(of_chiral.valid(b) == of_plain.valid(b));
        if (!of_chiral.valid(b)) continue;
        ++valid;
        for (int c = 0; c < 3; ++c) REQUIRE(of_chiral.at(b, c) == Approx(of_plain.at(b, c)).epsilon(1e-6));
    }
    CHECK(valid > of_chiral.bins() / 2);
    // Least squares fits the mirror mean too.
    const Compressed lsq_chiral = compress(chiral, "tabular:res=8x8x12,symmetry=bilateral,filter=lsq,ss=2");
    const Compressed lsq_plain = compress(plain, "tabular:res=8x8x12,symmetry=bilateral,filter=lsq,ss=2");
    const Table& a = dynamic_cast<const TabularBrdf&>(*lsq_chiral.brdf).table();
    const Table& b = dynamic_cast<const TabularBrdf&>(*lsq_plain.brdf).table();
    for (std::size_t k = 0; k < a.bins(); ++k)
        if (a.valid(k))
            for (int c = 0; c < 3; ++c) REQUIRE(a.at(k, c) == Approx(b.at(k, c)).epsilon(1e-4).margin(1e-7));
    // The non-reciprocity is kept: the reciprocal mean would have lost it.
    const TabularBrdf table{Table(of_chiral)};
    const double kept = reciprocity_error(table, directions()).cos_rmse_rel.mean;
    const double source = reciprocity_error(plain, directions()).cos_rmse_rel.mean;
    INFO("reciprocity error: the mirror mean's " << source << ", the table's " << kept);
    CHECK(source > 0.2);
    CHECK(kept == Approx(source).epsilon(0.15));
}

namespace {

// Each bilateral spec against the same with symmetry=none on twice the φd bins and with reciprocal ones
// on as many: as accurate as none over directions, and far better than reciprocal (on grids that resolve
// a lobe of roughness `alpha` well enough for the skew to dominate the reciprocal table's error).
void check_accuracy(std::initializer_list<const char*> bases, int bins, double alpha) {
    const Skewed src(0.8, 0.0, alpha);
    const std::string half = std::to_string(bins), full = std::to_string(2 * bins);
    for (const char* base : bases) {
        std::string spec = base;
        const auto with = [&](const std::string& np, const char* symmetry) {
            std::string s = spec;
            s.replace(s.find("NP"), 2, np);
            return s + ",symmetry=" + symmetry;
        };
        INFO(with(half, "bilateral"));
        const Compressed bil = compress(src, with(half, "bilateral")), none = compress(src, with(full, "none")),
                         rec = compress(src, with(half, "reciprocal"));
        CHECK(bil.brdf->bilateral());
        CHECK(!bil.brdf->reciprocal());
        CHECK(bil.brdf->nbytes() == rec.brdf->nbytes());
        const double e_bil = direction_error(src, *bil.brdf), e_none = direction_error(src, *none.brdf),
                     e_rec = direction_error(src, *rec.brdf);
        INFO("over directions: bilateral " << e_bil << ", none " << e_none << ", reciprocal " << e_rec);
        CHECK(e_bil < 1.1 * e_none);
        CHECK(e_rec > 2.0 * e_bil);
    }
}

}  // namespace

TEST_CASE("every kind with the bilateral fold is as accurate as symmetry=none at half the φd bins",
          "[bilateral][compress][heavy]") {
    check_accuracy({"tabular:res=32x32xNP", "tabular:res=32x32xNP,dtype=f16", "tabular:res=32x32xNP,dtype=u8log",
                    "tabular:res=16x16xNP,filter=lsq,ss=2", "svd:rank=6,space=log,res=32x32xNP",
                    "nmf:rank=6,res=32x32xNP",
                    "svd:rank=8,space=log,colour=shared,res=32x24xNP,dwarp=0.5,fit=lsq,weight=solid,dtype=f16"},
                   32, 0.12);
}

// The sanitizers' share of the test above: smaller grids, fewer kinds.
TEST_CASE("every kind with the bilateral fold is as accurate as symmetry=none at half the φd bins (small grids)",
          "[bilateral][compress][light]") {
    check_accuracy({"tabular:res=16x16xNP,dtype=f16", "tabular:res=8x8xNP,filter=lsq,ss=2",
                    "svd:rank=3,space=cos,colour=shared,res=12x8xNP,fit=lsq,weight=solid"},
                   12, 0.4);
}

TEST_CASE("symmetry=bilateral: which kinds take it, and a φh axis folds φh instead", "[bilateral][compress]") {
    const Skewed src(0.8, 0.0);
    CHECK_THROWS_WITH(compress(src, "bivariate:res=8x8,symmetry=bilateral"),
                      Catch::Contains("bivariate: symmetry=bilateral folds φd by the mirror, but a bivariate table "
                                      "averages φd away: use reciprocal or none"));
    CHECK_THROWS_WITH(compress(src, "pca:basis=x.brdfz,k=2,symmetry=bilateral"),
                      Catch::Contains("pca: symmetry=bilateral folds φd by the mirror"));
    std::vector<Table> tables;
    for (double a : {0.2, 0.5}) tables.push_back(tabulated(Skewed(a, 0.0), grid(8, 8, 8, Symmetry::Bilateral)));
    const std::vector<const Table*> ptrs{&tables[0], &tables[1]};
    CHECK_THROWS_WITH(train_pca_basis(ptrs), Catch::Contains("a basis's φd axis is reciprocal or none"));
    for (const char* spec : {"tabular:res=8x8x8,symmetry=bilateral", "svd:rank=2,res=8x8x8,symmetry=bilateral",
                             "nmf:rank=2,res=8x8x8,symmetry=bilateral,iterations=10"}) {
        INFO(spec);
        const Compressed c = compress(src, spec);
        REQUIRE(c.brdf->grid());
        CHECK(c.brdf->grid()->symmetry == Symmetry::Bilateral);
        CHECK(c.brdf->describe().find("symmetry bilateral") != std::string::npos);
    }
    // A bilateral table factored on its own grid keeps it.
    const TabularBrdf table(tabulated(src, grid(16, 16, 16, Symmetry::Bilateral)));
    CHECK(compress(table, "svd:rank=2").brdf->bilateral());
    CHECK(compress(table, "svd:rank=2,symmetry=reciprocal").brdf->reciprocal());
    // With phih >= 2 the word folds φh (repr/phi_h.h): no φd grid of one table.
    CHECK(compress(src, "tabular:res=8x4x8,phih=2,symmetry=bilateral").brdf->grid() == nullptr);
}

namespace {

void check_bilateral_samplers(std::size_t draws, test::Chi2Setting chi2) {
    const Skewed src(0.8, 0.0, 0.1);
    for (const char* spec : {"tabular:res=45x45x45,symmetry=bilateral", "tabular:res=45x45x45,symmetry=bilateral,dtype=f16",
                             "svd:rank=4,space=log,res=45x45x45,symmetry=bilateral"}) {
        INFO(spec);
        const Compressed c = compress(src, spec);
        test::check_sampler(*c.brdf, draws, test::kViewsLevel / 4, chi2);
        test::check_batch_bits(*c.brdf);
    }
    // The factor sampler of bilateral factors.
    const Compressed f = compress(src, "svd:rank=4,space=log,res=45x45x45,symmetry=bilateral");
    const auto& factored = dynamic_cast<const FactoredBrdf&>(*f.brdf);
    const FactorSampled factor_sampled(factored);
    test::check_sampler(factor_sampled, draws, test::kViewsLevel / 4, chi2);
}

}  // namespace

TEST_CASE("samplers of bilateral tables and factors: chi-square, normalisation, batches", "[bilateral][sample][heavy]") {
    check_bilateral_samplers(1000000, {test::Draws::Batch});
}

TEST_CASE("samplers of bilateral tables and factors, fewer draws", "[bilateral][sample][light]") {
    check_bilateral_samplers(200000, {test::Draws::Batch, 16});
}

TEST_CASE("the container stores bilateral tables and factors bit for bit, and says so", "[bilateral][container]") {
    test::TempDir dir;
    const Skewed src(0.8, 0.0);
    for (const char* spec : {"tabular:res=16x16x16,symmetry=bilateral", "tabular:res=16x16x16,symmetry=bilateral,dtype=f16",
                             "tabular:res=16x16x16,symmetry=bilateral,dtype=u8log",
                             "svd:rank=3,res=16x16x16,symmetry=bilateral,dtype=f16",
                             "nmf:rank=3,res=16x16x16,symmetry=bilateral,iterations=20"}) {
        INFO(spec);
        const Compressed c = compress(src, spec);
        const std::string path = (dir.path / "t.brdfz").string();
        save(*c.brdf, path);
        const container::ReadResult r = container::read(path);
        CHECK(r.meta.version == container::kVersion);
        CHECK(r.meta.min_reader_version == 5);
        bool listed = false;
        for (const container::Feature& f : r.meta.features) {
            listed = listed || (f.name.find("bilateral-phi-d") != std::string::npos && f.since == 5);
            CHECK(f.name.find("full-phi-d") == std::string::npos);
        }
        CHECK(listed);
        CHECK(r.brdf->bilateral());
        CHECK(r.brdf->nbytes() == c.brdf->nbytes());
        if (const Table* t = c.brdf->stored_table()) {
            REQUIRE(r.brdf->stored_table());
            CHECK(*r.brdf->stored_table() == *t);
        }
        if (const auto* t = dynamic_cast<const CompactTableBrdf*>(c.brdf.get())) {
            const auto* back = dynamic_cast<const CompactTableBrdf*>(r.brdf.get());
            REQUIRE(back);
            CHECK(back->table().grid() == t->table().grid());
            CHECK(back->table().codes() == t->table().codes());
        }
        if (const auto* f = dynamic_cast<const FactoredBrdf*>(c.brdf.get())) {
            const auto* back = dynamic_cast<const FactoredBrdf*>(r.brdf.get());
            REQUIRE(back);
            CHECK(back->factors().grid == f->factors().grid);
            CHECK(back->factors().u == f->factors().u);
            CHECK(back->factors().v == f->factors().v);
        }
        std::mt19937_64 rng(4);
        for (int k = 0; k < 1000; ++k) {
            const Vec3 wi = random_upper(rng), wo = random_upper(rng);
            REQUIRE(r.brdf->eval(wi, wo) == c.brdf->eval(wi, wo));
        }
    }
}

TEST_CASE("MERL files fold a bilateral table to the reciprocal mean on as many φd bins", "[bilateral][merl]") {
    test::TempDir dir;
    const Skewed src(0.8, 0.0);
    const TabularBrdf bil(tabulated(src, grid(16, 16, 16, Symmetry::Bilateral)));
    const std::string merl = (dir.path / "t.binary").string();
    save(bil, merl);
    const Loaded back = load(merl);
    const auto& folded = dynamic_cast<const TabularBrdf&>(*back.brdf).table();
    CHECK(folded.grid() == GridSpec{16, 16, 16});
    const TabularBrdf expect(tabulated(bil, GridSpec{16, 16, 16}));
    std::size_t valid = 0;
    for (std::size_t b = 0; b < folded.bins(); ++b)
        if (folded.valid(b)) {
            ++valid;
            REQUIRE(folded.at(b, 1) == Approx(expect.table().at(b, 1)).epsilon(1e-6));
        }
    CHECK(valid > folded.bins() / 2);
    // The reciprocal mean: φd and π − φd hold the same value.
    const GridSpec& g = folded.grid();
    const std::size_t a = g.index(3, 5, 2), b = g.index(3, 5, 13);
    REQUIRE(folded.valid(a));
    CHECK(folded.at(a, 1) == Approx(folded.at(b, 1)).epsilon(1e-5));
    SaveOptions o;
    o.grid = grid(16, 16, 16, Symmetry::Bilateral);
    CHECK_THROWS_WITH(save(bil, merl, o), Catch::Contains("symmetry bilateral needs .brdfz"));
}
