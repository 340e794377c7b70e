#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

#include "brdfz/compress.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/metrics.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/pca.h"
#include "brdfz/tabulate.h"
#include "sample_stats.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

const GridSpec kGrid{16, 16, 32, BinPosition::Centre};

// lambert+ggx: rho rgb, ks rgb, alpha, f0.
Table material(double alpha, double r, double g, double b, double ks, const GridSpec& grid = kGrid) {
    TabulateOptions o;
    o.grid = grid;
    return tabulate(AnalyticBrdf("lambert+ggx", {r, g, b, ks, ks, ks, alpha, 0.04}), o).table;
}

// A family of glossy materials with varied roughness and colour.
std::vector<Table> family() {
    std::vector<Table> out;
    const double alphas[] = {0.08, 0.12, 0.18, 0.25, 0.35, 0.5, 0.15, 0.3};
    for (int i = 0; i < 8; ++i)
        out.push_back(material(alphas[i], 0.1 + 0.08 * i, 0.5 - 0.05 * i, 0.2 + 0.03 * (i % 3), 0.3 + 0.08 * (i % 4)));
    return out;
}

std::vector<const Table*> pointers(const std::vector<Table>& tables) {
    std::vector<const Table*> p;
    for (const Table& t : tables) p.push_back(&t);
    return p;
}

// Root-mean-square difference, in the mapped space, between a table and its reconstruction from k
// coefficients, over the table's valid kept bins.
double mapped_error(const PcaBasis& basis, const Table& t, int k) {
    const std::vector<float> y = basis.map(t), r = basis.combine(basis.project(t, k));
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
        if (std::isnan(y[i])) continue;
        sum += (double(y[i]) - r[i]) * (double(y[i]) - r[i]);
        ++n;
    }
    REQUIRE(n > 0);
    return std::sqrt(sum / n);
}

std::shared_ptr<const PcaBasis> trained(const std::vector<Table>& tables, int k_max = 32) {
    PcaTrainOptions o;
    o.k_max = k_max;
    return std::make_shared<const PcaBasis>(train_pca_basis(pointers(tables), o));
}

}  // namespace

TEST_CASE("PCA: a training material at k = N-1 is reproduced, and beats a held-out one", "[pca]") {
    const std::vector<Table> tables = family();
    PcaTrainReport report;
    PcaTrainOptions o;
    const PcaBasis basis = train_pca_basis(pointers(tables), o, &report);
    // Centring leaves N-1 directions: that many components, explaining all the variance.
    REQUIRE(basis.k_max() == 7);
    CHECK(report.dropped_bins > 0);  // bins with a direction below the horizon
    CHECK(report.kept_bins + report.dropped_bins == kGrid.bins());
    CHECK(report.imputed_values == 0);
    double sum = 0;
    for (double v : report.variances) sum += v;
    CHECK(sum == Approx(report.total_variance).epsilon(1e-4));
    for (std::size_t j = 1; j < report.variances.size(); ++j) CHECK(report.variances[j] <= report.variances[j - 1]);

    // Orthonormal components.
    const Eigen::Map<const Eigen::MatrixXf> b(basis.components().data(), static_cast<Eigen::Index>(basis.dims()), basis.k_max());
    const Eigen::MatrixXd gram = (b.transpose() * b).cast<double>();
    CHECK((gram - Eigen::MatrixXd::Identity(7, 7)).cwiseAbs().maxCoeff() < 1e-4);

    for (const Table& t : tables) CHECK(mapped_error(basis, t, 7) < 1e-5);

    // Held out: rougher than anything in training and an unseen colour.
    const Table held = material(0.8, 0.7, 0.05, 0.6, 0.9);
    for (int k : {2, 4, 7}) {
        const double train_err = mapped_error(basis, tables[3], k), held_err = mapped_error(basis, held, k);
        INFO("k = " << k << ": training " << train_err << ", held out " << held_err);
        CHECK(train_err < held_err);
    }
    // The same in the metrics a user sees (f_r·cos), through the reconstructed table.
    const auto shared = std::make_shared<const PcaBasis>(basis);
    const PcaBrdf train_pca(shared, basis.project(tables[3], 4)), held_pca(shared, basis.project(held, 4));
    const Metrics mt = compare(TabularBrdf(tables[3]), train_pca), mh = compare(TabularBrdf(held), held_pca);
    CHECK(mt.log_rmse.mean < mh.log_rmse.mean);
    CHECK(mt.cos_rmse_rel.mean < mh.cos_rmse_rel.mean);
}

TEST_CASE("PCA: outputs are finite and >= 0 on 10^6 random pairs, with clamping counted", "[pca]") {
    const std::vector<Table> tables = family();
    const auto basis = trained(tables, 4);
    // A held-out material, poorly described by 4 components, and far-out coefficients.
    const Table held = material(0.03, 0.9, 0.9, 0.01, 1.0);
    std::vector<float> wild(4);
    for (int j = 0; j < 4; ++j) wild[j] = (j % 2 ? -1.0f : 1.0f) * 40.0f * std::sqrt(float(basis->variances()[j]));
    for (const std::vector<float>& c : {basis->project(held, 4), wild}) {
        const PcaBrdf pca(basis, c);
        // The count is of values the inverse mapping takes below 0: recount them from combine().
        const std::vector<float> y = basis->combine(c);
        std::size_t negative = 0, kept = 0;
        for (std::size_t bin = 0; bin < kGrid.bins(); ++bin) {
            if (std::isnan(basis->median()[3 * bin])) continue;
            ++kept;
            const auto [wi, wo] = from_half_diff({kGrid.theta_h_at(bin / (16 * 32)), 0.0,
                                                  kGrid.theta_d_at(bin / 32 % 16), kGrid.phi_d_at(bin % 32)});
            const double w = static_cast<float>(wi.z * wo.z);  // as the basis keeps it
            bool neg = false;
            for (int ch = 0; ch < 3; ++ch) {
                const double m = basis->median()[3 * bin + ch];
                neg = neg || std::exp(double(y[3 * bin + ch])) * (m * w + basis->epsilon()) - basis->epsilon() < 0.0;
            }
            negative += neg;
        }
        CHECK(pca.counts().clamped == negative);
        CHECK(pca.counts().valid + pca.counts().inf == kept);

        std::mt19937 rng(7);
        std::normal_distribution<double> n01;
        std::size_t bad = 0;
        const int pairs = 1000000;
        std::vector<Vec3> wi(pairs), wo(pairs);
        for (int k = 0; k < pairs; ++k) {
            wi[k] = normalize(Vec3{n01(rng), n01(rng), n01(rng)});
            wo[k] = normalize(Vec3{n01(rng), n01(rng), n01(rng)});
        }
        std::vector<Rgb> out(pairs);
        pca.eval(wi, wo, out);
        for (const Rgb& f : out)
            for (double v : f) bad += !(std::isfinite(v) && v >= 0.0);
        CHECK(bad == 0);
    }
    CHECK(PcaBrdf(basis, wild).counts().clamped > 0);  // the far-out coefficients do go negative
}

TEST_CASE("PCA: invalid bins neither poison the basis nor pull projections", "[pca]") {
    std::vector<Table> tables = family();
    const GridSpec& g = kGrid;
    // A bin missing in most tables is dropped; one missing in a single table is imputed.
    const std::size_t often = g.index(2, 3, 4), once = g.index(5, 6, 7);
    for (std::size_t t = 0; t < 6; ++t) tables[t].invalidate(often);
    tables[1].invalidate(once);
    tables[2].data()[3 * g.index(3, 3, 3) + 1] = -1.0f;  // a negative value is invalid too
    PcaTrainReport report;
    const PcaBasis basis = train_pca_basis(pointers(tables), {}, &report);
    CHECK(std::isnan(basis.median()[3 * often]));
    CHECK(!std::isnan(basis.median()[3 * once]));
    CHECK(report.imputed_values == 6);  // two bins, three channels each
    for (float v : basis.components()) REQUIRE(std::isfinite(v));

    // A training material with a third of its bins missing projects onto nearly the same coefficients
    // as the whole material: least squares over its own valid bins.
    const std::vector<float> whole = basis.project(tables[4], 7);
    Table holed = tables[4];
    std::mt19937 rng(3);
    for (std::size_t bin = 0; bin < g.bins(); ++bin)
        if (rng() % 3 == 0) holed.invalidate(bin);
    const std::vector<float> part = basis.project(holed, 7);
    for (int j = 0; j < 7; ++j) CHECK(part[j] == Approx(whole[j]).margin(1e-3));
    // The reconstruction leaves dropped bins invalid.
    const PcaBrdf pca(std::make_shared<const PcaBasis>(basis), part);
    CHECK(!pca.table().table().valid(often));
}

TEST_CASE("PCA: bad input gives clear errors", "[pca]") {
    const std::vector<Table> tables = family();
    CHECK_THROWS_WITH(train_pca_basis({}), Catch::Contains("at least 2 tables"));
    const std::vector<const Table*> one{&tables[0]};
    CHECK_THROWS_AS(train_pca_basis(one), ValueError);
    const Table other = material(0.2, 0.3, 0.3, 0.3, 0.5, GridSpec{8, 8, 16});
    const std::vector<const Table*> mixed{&tables[0], &tables[1], &other};
    CHECK_THROWS_WITH(train_pca_basis(mixed), Catch::Contains("all must share one grid"));
    const std::vector<const Table*> same{&tables[0], &tables[0], &tables[0]};
    CHECK_THROWS_WITH(train_pca_basis(same), Catch::Contains("do not differ"));
    PcaTrainOptions o;
    o.k_max = 0;
    CHECK_THROWS_AS(train_pca_basis(pointers(tables), o), ValueError);

    const auto basis = trained(tables, 3);
    CHECK_THROWS_WITH(basis->project(other, 2), Catch::Contains("does not fit the basis's grid"));
    CHECK_THROWS_AS(basis->project(tables[0], 4), ValueError);
    CHECK_THROWS_AS(PcaBrdf(basis, {1.0f, 2.0f, 3.0f, 4.0f}), ValueError);
    CHECK_THROWS_AS(PcaBrdf(basis, {std::nanf("")}), ValueError);
    // Nothing valid to project from.
    CHECK_THROWS_WITH(basis->project(Table(kGrid), 2), Catch::Contains("too few"));
}

// A PCA material samples as its reconstructed table does (the tabular sampler, tested in
// sample_test.cpp): the sampler's checks on a held-out material, and every draw the table's.
TEST_CASE("PCA: sampling is the reconstructed table's, one call or a batch", "[pca][sample]") {
    const std::vector<Table> tables = family();
    const auto basis = trained(tables, 6);
    const PcaBrdf pca(basis, basis->project(material(0.1, 0.6, 0.3, 0.2, 0.5), 6));
    test::check_sampler(pca, 200000);

    // Random views, a tenth of them below the horizon, and u: the same results whichever way.
    const std::size_t count = 1000;
    auto [wo, us] = test::random_views(count, 11);
    for (std::size_t k = 0; k < count; k += 10) wo[k].z = -wo[k].z;
    std::vector<BrdfSample> batch(count), table_batch(count);
    pca.sample(wo, us, batch);
    pca.table().sample(wo, us, table_batch);
    std::size_t drawn = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const BrdfSample one = pca.sample(wo[k], us[k][0], us[k][1]);
        REQUIRE(std::memcmp(&one, &batch[k], sizeof one) == 0);
        REQUIRE(std::memcmp(&one, &table_batch[k], sizeof one) == 0);
        if (one.pdf == 0) continue;
        ++drawn;
        REQUIRE(pca.pdf(wo[k], one.wi) == Approx(one.pdf).epsilon(1e-9));
    }
    CHECK(drawn > count / 2);
}

TEST_CASE("PCA: nbytes counts the per-material part, the basis its own", "[pca]") {
    const std::vector<Table> tables = family();
    const auto basis = trained(tables, 5);
    const PcaBrdf pca(basis, basis->project(tables[0], 5));
    CHECK(pca.nbytes() == 5 * 4 + 32);
    CHECK(basis->nbytes() == (2 + 5) * kGrid.bins() * 3 * 4 + 5 * 8);
}

TEST_CASE("PCA container: basis file and materials round-trip, hash and files checked", "[pca][container]") {
    test::TempDir dir;
    const std::vector<Table> tables = family();
    const auto basis = trained(tables, 5);
    const fs::path basis_path = dir.path / "basis.brdfz";
    const auto written = container::write_pca_basis(basis_path.string(), *basis);
    const auto loaded = container::read_pca_basis(basis_path.string());
    CHECK(loaded->origin().sha256 == container::pca_basis_sha256(*basis));
    CHECK(written->origin().sha256 == loaded->origin().sha256);
    CHECK(written->origin().path == basis_path.string());
    CHECK(loaded->origin().sha256.size() == 64);
    CHECK(std::equal(loaded->components().begin(), loaded->components().end(), basis->components().begin()));
    CHECK(std::equal(loaded->mean().begin(), loaded->mean().end(), basis->mean().begin()));
    // Bit for bit, NaN medians included.
    CHECK(std::memcmp(loaded->median().data(), basis->median().data(), basis->median().size_bytes()) == 0);

    const std::vector<float> coefficients = loaded->project(tables[2], 4);
    const PcaBrdf referenced(loaded, coefficients);
    const fs::path mat = dir.path / "mat.brdfz";
    const container::Achieved a = container::write(mat.string(), referenced);
    CHECK(a.lossless);
    CHECK(a.nbytes == 4 * 4 + 32);
    const container::Metadata meta = container::read_metadata(mat.string());
    CHECK(meta.representation == "pca");
    CHECK(std::find(meta.features.begin(), meta.features.end(), container::Feature{"pca.external-basis", 2}) !=
          meta.features.end());
    CHECK(fs::file_size(mat) < 64 * 1024);  // the basis is not in it

    const auto check_same = [&](const fs::path& p) {
        container::ReadResult r = container::read(p.string());
        const auto* back = dynamic_cast<const PcaBrdf*>(r.brdf.get());
        REQUIRE(back);
        CHECK(std::equal(back->coefficients().begin(), back->coefficients().end(), coefficients.begin(), coefficients.end()));
        CHECK(back->table().table() == referenced.table().table());
        return back->basis_storage();
    };
    CHECK(check_same(mat) == PcaBrdf::BasisStorage::Referenced);
    // A material file is not a basis file.
    CHECK_THROWS_WITH(container::read_pca_basis(mat.string()), Catch::Contains("not a PCA basis file"));
    // Loading by extension goes through the same reader.
    CHECK(dynamic_cast<const PcaBrdf*>(load(mat.string()).brdf.get()));

    // Embedded: one self-contained file.
    const fs::path emb = dir.path / "embedded.brdfz";
    container::write(emb.string(), PcaBrdf(loaded, coefficients, Lookup::Linear, PcaBrdf::BasisStorage::Embedded));
    CHECK(check_same(emb) == PcaBrdf::BasisStorage::Embedded);

    // A basis in another directory is found relative to the material.
    fs::create_directories(dir.path / "sub");
    const fs::path nested = dir.path / "sub" / "mat.brdfz";
    container::write(nested.string(), referenced);
    CHECK(check_same(nested) == PcaBrdf::BasisStorage::Referenced);

    // A material cannot reference a basis that was never written.
    CHECK_THROWS_WITH(container::write((dir.path / "x.brdfz").string(), PcaBrdf(basis, coefficients)),
                      Catch::Contains("cannot be referenced"));
    CHECK(!fs::exists(dir.path / "x.brdfz"));

    // A retrained basis in the basis's place: the hash no longer matches.
    std::vector<Table> fewer(tables.begin(), tables.begin() + 6);
    container::write_pca_basis(basis_path.string(), *trained(fewer, 5));
    CHECK_THROWS_AS(container::read(mat.string()), FormatError);
    CHECK_THROWS_WITH(container::read(mat.string()), Catch::Contains("content hash") && Catch::Contains("basis.brdfz"));
    // The embedded material does not depend on the basis file.
    CHECK(check_same(emb) == PcaBrdf::BasisStorage::Embedded);

    // Missing basis file: named.
    fs::remove(basis_path);
    CHECK_THROWS_AS(container::read(mat.string()), IoError);
    CHECK_THROWS_WITH(container::read(mat.string()), Catch::Contains("basis.brdfz") && Catch::Contains("not found"));

    const fs::path table_file = dir.path / "table.brdfz";
    container::write(table_file.string(), TabularBrdf(tables[0]));
    CHECK_THROWS_WITH(container::read_pca_basis(table_file.string()), Catch::Contains("not a PCA basis file"));
}

TEST_CASE("PCA container: a flipped byte in the basis file is detected", "[pca][container]") {
    test::TempDir dir;
    const std::vector<Table> tables = family();
    const auto basis = trained(tables, 3);
    const fs::path basis_path = dir.path / "basis.brdfz", mat = dir.path / "mat.brdfz";
    container::write_pca_basis(basis_path.string(), *basis);
    container::write(mat.string(), PcaBrdf(container::read_pca_basis(basis_path.string()), {0.5f, -0.25f}));
    const std::uintmax_t size = fs::file_size(basis_path);
    std::vector<char> bytes(size);
    {
        std::ifstream in(basis_path, std::ios::binary);
        in.read(bytes.data(), static_cast<std::streamsize>(size));
    }
    std::mt19937 rng(11);
    for (int trial = 0; trial < 20; ++trial) {
        const std::size_t at = rng() % size;
        std::vector<char> damaged = bytes;
        damaged[at] = static_cast<char>(damaged[at] ^ 0x10);
        {
            std::ofstream out(basis_path, std::ios::binary | std::ios::trunc);
            out.write(damaged.data(), static_cast<std::streamsize>(size));
        }
        INFO("byte " << at);
        CHECK_THROWS_AS(container::read(mat.string()), FormatError);
    }
}

TEST_CASE("PCA: compress kind pca:basis=FILE,k=K", "[pca][compress]") {
    test::TempDir dir;
    const std::vector<Table> tables = family();
    const fs::path basis_path = dir.path / "basis.brdfz";
    container::write_pca_basis(basis_path.string(), *trained(tables, 6));
    const std::string spec = "pca:basis=" + basis_path.string() + ",k=3";
    // The core reads no files: the basis comes through the formats library's file access.
    const CompressOptions files = with_file_access({});
    const Compressed c = compress(TabularBrdf(tables[1]), spec, files);
    const auto* pca = dynamic_cast<const PcaBrdf*>(c.brdf.get());
    REQUIRE(pca);
    CHECK(pca->k() == 3);
    CHECK(c.brdf->nbytes() == 3 * 4 + 32);
    // A source that is not a table on the basis's grid is tabulated onto it first.
    const AnalyticBrdf analytic("lambert+ggx", {0.2, 0.3, 0.4, 0.5, 0.5, 0.5, 0.2, 0.04});
    CHECK(dynamic_cast<const PcaBrdf*>(compress(analytic, spec, files).brdf.get())->k() == 3);
    CHECK_THROWS_WITH(compress(analytic, "pca:k=3", files), Catch::Contains("name the basis file"));
    CHECK_THROWS_WITH(compress(analytic, "pca:basis=" + basis_path.string() + ",k=9", files),
                      Catch::Contains("has 6 components"));
    CHECK_THROWS_AS(compress(analytic, "pca:basis=" + (dir.path / "none.brdfz").string() + ",k=2", files), IoError);
    CHECK_THROWS_WITH(compress(analytic, spec), Catch::Contains("load_pca_basis is unset"));
}

TEST_CASE("PCA on real MERL tables: training beats held out", "[pca][merl][heavy]") {
    const std::vector<fs::path> files = test::merl_tables();
    if (files.size() < 4) {
        WARN("skipped: fewer than 4 MERL tables in BRDFZ_MERL_DIR (generated from ../shared by ctest)");
        return;
    }
    // Train on all but the last; hold the last out.
    std::vector<Table> tables;
    for (const fs::path& f : files) tables.push_back(dynamic_cast<const TabularBrdf&>(*load(f.string()).brdf).table());
    const Table held = tables.back();
    tables.pop_back();
    const auto basis = trained(tables);
    const int k = basis->k_max();
    REQUIRE(k == static_cast<int>(tables.size()) - 1);
    INFO("held out: " << files.back().filename());
    for (const Table& t : tables) CHECK(mapped_error(*basis, t, k) < 1e-4);
    const PcaBrdf train_pca(basis, basis->project(tables[0], k)), held_pca(basis, basis->project(held, k));
    const Metrics mt = compare(TabularBrdf(tables[0]), train_pca), mh = compare(TabularBrdf(held), held_pca);
    CHECK(mt.log_rmse.mean < 1e-3);
    CHECK(mt.log_rmse.mean < mh.log_rmse.mean);
    CHECK(mt.cos_rmse_rel.mean < mh.cos_rmse_rel.mean);
    // The held-out reconstruction samples with an exact pdf, as any table does.
    test::check_sampler(held_pca, 300000);
}
