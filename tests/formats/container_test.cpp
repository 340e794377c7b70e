#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/merl.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/compress.h"
#include "container/checksum.h"
#include "container/h5.h"
#include "container/storage.h"
#include "test_util.h"

using namespace brdfz;
namespace fs = std::filesystem;

namespace {

std::vector<unsigned char> slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void spit(const fs::path& p, const std::vector<unsigned char>& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// A table with random positive values, some NaN entries (one with a non-default payload) and a
// resolution unlike MERL's.
Table random_table(GridSpec g, std::uint32_t seed) {
    Table t(g);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 3.0f);
    for (std::size_t k = 0; k < 3 * t.bins(); ++k) t.data()[k] = u(rng);
    for (std::size_t k = 0; k < 3 * t.bins(); k += 7) t.data()[k] = std::numeric_limits<float>::quiet_NaN();
    const std::uint32_t payload = 0x7fc01234u;
    std::memcpy(t.data() + 1, &payload, 4);
    return t;
}

// A small but valid set of RGL tensors: 3 θi slices, 4×5 grids.
rgl::Tensors small_tensors() {
    rgl::Tensors t;
    t.theta_i = {0.0f, 0.6f, 1.2f};
    const auto grids = [](std::size_t slices, std::uint32_t seed) {
        rgl::Grids g;
        g.slices = slices;
        g.rows = 4;
        g.cols = 5;
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.1f, 2.0f);
        g.values.resize(slices * 20);
        for (float& v : g.values) v = u(rng);
        return g;
    };
    t.ndf = grids(1, 1);
    t.sigma = grids(1, 2);
    t.vndf = grids(3, 3);
    t.rgb = grids(9, 4);
    t.luminance = grids(3, 5);
    return t;
}

// The dataset extents recorded in a container's header (formats/SPEC.md §1).
std::vector<std::pair<std::uint64_t, std::uint64_t>> extents_of(const std::vector<unsigned char>& file) {
    const auto u32 = [&](std::size_t at) {
        std::uint32_t v;
        std::memcpy(&v, file.data() + at, 4);
        return v;
    };
    const auto u64 = [&](std::size_t at) {
        std::uint64_t v;
        std::memcpy(&v, file.data() + at, 8);
        return v;
    };
    std::vector<std::pair<std::uint64_t, std::uint64_t>> out;
    for (std::uint32_t k = 0; k < u32(12); ++k) out.emplace_back(u64(32 + 16 * k), u64(40 + 16 * k));
    return out;
}

std::string read_error(const fs::path& p) {
    try {
        container::read(p.string());
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// The header (formats/SPEC.md §1) recomputed for a file whose HDF5 part was edited on purpose.
void reseal(const fs::path& p) {
    std::vector<unsigned char> f = slurp(p);
    const auto ext = extents_of(f);
    std::uint32_t crc = 0;
    std::uint64_t pos = 4096;
    for (const auto& [off, len] : ext) {
        crc = container::crc32c(f.data() + pos, off - pos, crc);
        pos = off + len;
    }
    crc = container::crc32c(f.data() + pos, f.size() - pos, crc);
    const std::uint64_t size = f.size();
    std::memcpy(f.data() + 16, &size, 8);
    std::memcpy(f.data() + 24, &crc, 4);
    const std::uint32_t hcrc = container::crc32c(f.data(), 4092);
    std::memcpy(f.data() + 4092, &hcrc, 4);
    spit(p, f);
}

}  // namespace

TEST_CASE("CRC-32C and SHA-256 match their standard check values", "[container][checksum][qemu]") {
    CHECK(container::crc32c("123456789", 9) == 0xE3069283u);
    CHECK(container::crc32c("", 0) == 0u);

    // Bit-at-a-time reference against the fast path, across the three-stream block boundaries, and
    // chaining: crc(A‖B) == crc(B, crc(A)).
    const auto reference = [](const unsigned char* p, std::size_t n) {
        std::uint32_t c = 0xFFFFFFFFu;
        for (std::size_t k = 0; k < n; ++k) {
            c ^= p[k];
            for (int b = 0; b < 8; ++b) c = (c >> 1) ^ (c & 1 ? 0x82F63B78u : 0);
        }
        return ~c;
    };
    std::vector<unsigned char> data(100000);
    std::mt19937 rng(7);
    for (auto& b : data) b = static_cast<unsigned char>(rng());
    for (std::size_t n : {1u, 7u, 8u, 24575u, 24576u, 24577u, 49153u, 100000u}) {
        INFO("n = " << n);
        CHECK(container::crc32c(data.data(), n) == reference(data.data(), n));
        const std::size_t cut = n / 3;
        CHECK(container::crc32c(data.data() + cut, n - cut, container::crc32c(data.data(), cut)) ==
              reference(data.data(), n));
    }

    const auto sha = [](const std::string& s) {
        container::Sha256 h;
        h.update(s.data(), s.size());
        return container::hex(h.finish());
    };
    CHECK(sha("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    CHECK(sha("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    CHECK(sha("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
          "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    container::Sha256 million;
    const std::string a(1000, 'a');
    for (int k = 0; k < 1000; ++k) million.update(a.data(), a.size());
    CHECK(container::hex(million.finish()) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE("Tables round-trip through .brdfz bit for bit", "[container][qemu]") {
    test::TempDir dir;
    for (const GridSpec& g : {GridSpec{7, 5, 11, BinPosition::Start}, GridSpec{90, 90, 180, BinPosition::Centre},
                              GridSpec{1, 1, 1, BinPosition::Centre}}) {
        INFO(g.str());
        const Table table = random_table(g, 3);
        const fs::path p = dir.path / ("t" + g.str() + ".brdfz");
        const container::Achieved a = container::write(p.string(), TabularBrdf(table, Lookup::Nearest));
        CHECK(a.lossless);
        CHECK(!a.metrics);
        CHECK(a.nbytes == table.bins() * 12);

        const container::ReadResult r = container::read(p.string(), Lookup::Nearest);
        const auto* back = dynamic_cast<const TabularBrdf*>(r.brdf.get());
        REQUIRE(back);
        CHECK(back->table() == table);  // grid, bin position and every bit, NaN payloads included
        CHECK(back->lookup() == Lookup::Nearest);
        CHECK(r.meta.representation == "tabular");
        CHECK(r.meta.version == container::kVersion);
        CHECK(r.meta.min_reader_version == 1);
        CHECK(r.meta.features ==
              std::vector<container::Feature>{{"core", 1}, {"tabular", 1}, {"tabular.float32", 1}});
        CHECK(r.meta.units == "1/sr");
        CHECK(r.meta.cosine == "excluded");
        CHECK(r.meta.created.size() == 20);
        CHECK(!r.meta.library_version.empty());
        CHECK(r.meta.spec == TabularBrdf(table, Lookup::Nearest).describe());
        CHECK(r.meta.achieved.lossless);
        CHECK(r.meta.achieved.counts.valid == table.valid_bins());
    }
    // No temporary files are left behind.
    for (const auto& e : fs::directory_iterator(dir.path))
        CHECK(e.path().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("Compact tables (float16, u8log, bivariate) round-trip through .brdfz bit for bit",
          "[container][compact][qemu]") {
    test::TempDir dir;
    const std::vector<Vec3> wi{normalize(Vec3{0.3, -0.2, 0.9}), normalize(Vec3{-0.7, 0.1, 0.2}), {0, 0, 1}},
        wo{normalize(Vec3{-0.1, 0.4, 0.8}), normalize(Vec3{0.6, 0.5, 0.3}), normalize(Vec3{0.9, 0, 0.1})};
    for (const GridSpec& g : {GridSpec{7, 5, 11, BinPosition::Start}, GridSpec{32, 16, 1, BinPosition::Centre}})
        for (TableDtype dtype : {TableDtype::F16, TableDtype::U8Log}) {
            INFO(g.str() << " " << table_dtype_name(dtype));
            const CompactTableBrdf table(CompactTable::encode(random_table(g, 4), dtype), Lookup::Nearest);
            const fs::path p = dir.path / ("c" + g.str() + table_dtype_name(dtype) + ".brdfz");
            const container::Achieved a = container::write(p.string(), table);
            CHECK(a.lossless);
            CHECK(a.nbytes == table.nbytes());
            CHECK(a.nbytes == g.bins() * 3 * (dtype == TableDtype::F16 ? 2 : 1) + 72);

            const container::ReadResult r = container::read(p.string(), Lookup::Nearest);
            const auto* back = dynamic_cast<const CompactTableBrdf*>(r.brdf.get());
            REQUIRE(back);
            CHECK(back->table() == table.table());  // grid, codes and codec parameters, bit for bit
            for (std::size_t k = 0; k < wi.size(); ++k) CHECK(back->eval(wi[k], wo[k]) == table.eval(wi[k], wo[k]));
            CHECK(r.meta.version == container::kVersion);
            CHECK(r.meta.min_reader_version == 2);
            const container::Feature element =
                dtype == TableDtype::F16 ? container::Feature{"tabular.float16", 2} : container::Feature{"tabular.uint8-log", 2};
            CHECK(r.meta.features == std::vector<container::Feature>{{"core", 1}, {"tabular", 1}, element});
            CHECK(r.meta.spec == table.describe());
            CHECK(r.meta.achieved.counts.valid == table.table().valid_bins());
            const container::Metadata meta = container::read_metadata(p.string());
            REQUIRE(meta.datasets.size() == 1);  // the representation's own; its sampler's are in a subgroup
            CHECK(meta.datasets[0].path == "/representation/values");
            CHECK(meta.datasets[0].dtype == (dtype == TableDtype::F16 ? "float16" : "uint8"));
            CHECK(meta.datasets[0].shape == std::vector<std::uint64_t>{std::uint64_t(g.n_theta_h), std::uint64_t(g.n_theta_d),
                                                                        std::uint64_t(g.n_phi_d), 3});

            // A flipped byte in the codes is detected and the dataset named.
            std::vector<unsigned char> bytes = slurp(p);
            const auto extents = extents_of(bytes);
            REQUIRE(extents.size() == 5);          // the codes, then the compact sampler's four tables
            const auto codes = extents.front();  // written first
            REQUIRE(codes.second == table.table().codes().size());
            for (std::uint64_t at : {codes.first, codes.first + codes.second - 1}) {
                std::vector<unsigned char> b = bytes;
                b[at] ^= 0x04;
                const fs::path bad = dir.path / "bad.brdfz";
                spit(bad, b);
                CHECK_THAT(read_error(bad), Catch::Contains("dataset /representation/values is corrupt"));
            }
        }
}

TEST_CASE("Tables on a warped θd axis round-trip through .brdfz with their axis", "[container][warp]") {
    test::TempDir dir;
    const std::vector<Vec3> wi{normalize(Vec3{0.3, -0.2, 0.9}), normalize(Vec3{-0.7, 0.1, 0.2}), {0, 0, 1}},
        wo{normalize(Vec3{-0.1, 0.4, 0.8}), normalize(Vec3{0.6, 0.5, 0.3}), normalize(Vec3{0.9, 0, 0.1})};
    const GridSpec g{7, 9, 5, BinPosition::Centre, 0.65};
    const Table table = random_table(g, 5);
    const TabularBrdf f32(table);
    const CompactTableBrdf u8(CompactTable::encode(table, TableDtype::U8Log));
    for (const Brdf* b : {static_cast<const Brdf*>(&f32), static_cast<const Brdf*>(&u8)}) {
        INFO(b->describe());
        const fs::path p = dir.path / "warped.brdfz";
        const container::Achieved a = container::write(p.string(), *b);
        CHECK(a.lossless);
        CHECK(a.nbytes == b->nbytes());
        const container::ReadResult r = container::read(p.string());
        CHECK(r.brdf->describe() == b->describe());
        for (std::size_t k = 0; k < wi.size(); ++k) CHECK(r.brdf->eval(wi[k], wo[k]) == b->eval(wi[k], wo[k]));
        if (const auto* back = dynamic_cast<const TabularBrdf*>(r.brdf.get())) {
            CHECK(back->table() == table);  // grid (warp included) and every bit
        } else {
            const auto* c = dynamic_cast<const CompactTableBrdf*>(r.brdf.get());
            REQUIRE(c);
            CHECK(c->table() == u8.table());
        }
        CHECK(r.meta.features.back() == container::Feature{"tabular.warped-theta-d", 2});
        CHECK(r.meta.min_reader_version == 2);
    }
    // A linear table does not list the feature (older readers open it).
    const fs::path p = dir.path / "linear.brdfz";
    container::write(p.string(), TabularBrdf(random_table({7, 9, 5}, 5)));
    for (const container::Feature& f : container::read(p.string()).meta.features) CHECK(f.name != "tabular.warped-theta-d");

    // MERL and EXR files have only the linear θd axis: a warped table is tabulated onto its own grid on
    // that axis, not written as if its bins were linear.
    Table smooth(GridSpec{8, 16, 8, BinPosition::Centre, 0.8});
    for (std::size_t bin = 0; bin < smooth.bins(); ++bin) smooth.set(bin, {1.0, 2.0, 0.5 + bin % 16 * 0.1});
    const TabularBrdf warped(smooth);
    for (const char* ext : {".binary", ".exr"}) {
        INFO(ext);
        const fs::path q = dir.path / (std::string("warped") + ext);
        save(warped, q.string());
        const Loaded back = load(q.string());
        const auto& t = dynamic_cast<const TabularBrdf&>(*back.brdf).table();
        CHECK(t.grid() == GridSpec{8, 16, 8});
        // θd bin centres of the linear grid read the warped table's interpolation there.
        for (int id = 0; id < 16; ++id) {
            const auto [a, b] = from_half_diff({t.grid().theta_h_at(2), 0.0, t.grid().theta_d_at(id), t.grid().phi_d_at(3)});
            if (!(a.z > 0 && b.z > 0)) continue;
            CHECK(back.brdf->eval(a, b)[2] == Approx(warped.eval(a, b)[2]).epsilon(1e-6));
        }
    }
}

TEST_CASE("Metadata lists datasets and records the source", "[container]") {
    test::TempDir dir;
    const fs::path src = dir.path / "src.binary", out = dir.path / "out.brdfz";
    const Table table = random_table({6, 4, 8}, 5);
    merl::write(src.string(), table);
    SaveOptions s;
    s.source = src.string();
    s.source_format = "merl";
    save(TabularBrdf(table), out.string(), s);

    const container::Metadata m = container::read_metadata(out.string());
    CHECK(m.source.file == "src.binary");
    CHECK(m.source.format == "merl");
    CHECK(m.source.sha256 == container::sha256_file(src.string()));
    REQUIRE(m.datasets.size() == 1);
    CHECK(m.datasets[0].path == "/representation/values");
    CHECK(m.datasets[0].dtype == "float32");
    CHECK(m.datasets[0].shape == std::vector<std::uint64_t>{6, 4, 8, 3});
    CHECK(m.datasets[0].crc32c == container::crc32c(table.data(), table.bins() * 12));

    // load() by extension, and load_as() whatever the extension.
    const Loaded l = load(out.string());
    CHECK(l.info.format == "brdfz");
    CHECK(l.info.dims == std::vector<std::size_t>{6, 4, 8});
    CHECK(dynamic_cast<const TabularBrdf&>(*l.brdf).table() == table);
    const fs::path renamed = dir.path / "out.data";
    fs::copy_file(out, renamed);
    CHECK(dynamic_cast<const TabularBrdf&>(*load_as("brdfz", renamed.string()).brdf).table() == table);
}

TEST_CASE("Non-tabular sources are tabulated and their achieved error recorded", "[container]") {
    test::TempDir dir;
    const fs::path p = dir.path / "cd.brdfz";
    const CoatedDiffuse material;
    container::WriteOptions w;
    w.grid = GridSpec{16, 16, 32};
    const container::Achieved a = container::write(p.string(), material, w);
    CHECK(!a.lossless);
    REQUIRE(a.metrics);
    CHECK(a.metrics->samples > 0);
    CHECK(a.counts.below_horizon > 0);

    const container::ReadResult r = container::read(p.string());
    CHECK(!r.meta.achieved.lossless);
    REQUIRE(r.meta.achieved.metrics);
    CHECK(r.meta.achieved.metrics->cos_rmse.mean == a.metrics->cos_rmse.mean);
    CHECK(r.meta.achieved.metrics->samples == a.metrics->samples);
    CHECK(r.meta.achieved.counts.below_horizon == a.counts.below_horizon);
    CHECK(dynamic_cast<const TabularBrdf&>(*r.brdf).table().grid() == *w.grid);

    // A table asked for on another grid is resampled, on its own grid stored as it is.
    const Table t = random_table({8, 8, 8}, 9);
    w.grid = GridSpec{4, 4, 4};
    CHECK(!container::write(p.string(), TabularBrdf(t), w).lossless);
    w.grid = t.grid();
    CHECK(container::write(p.string(), TabularBrdf(t), w).lossless);
}

TEST_CASE("RGL tensors round-trip through .brdfz bit for bit", "[container][rgl][qemu]") {
    test::TempDir dir;
    std::vector<std::unique_ptr<rgl::RglBrdf>> sources;
    sources.push_back(std::make_unique<rgl::RglBrdf>(small_tensors()));
    {  // anisotropic: the same grids over 2 φi slices
        rgl::Tensors t = small_tensors();
        t.phi_i = {-3.0f, 0.5f, 3.0f};
        for (rgl::Grids* g : {&t.vndf, &t.rgb, &t.luminance}) {
            const std::vector<float> one = g->values;
            for (int k = 0; k < 2; ++k)
                for (float v : one) g->values.push_back(v * (1.5f + k));
            g->slices *= 3;
        }
        sources.push_back(std::make_unique<rgl::RglBrdf>(std::move(t)));
    }
    const fs::path shared = fs::path(BRDFZ_SHARED_DIR) / "data" / "rgl";
    std::error_code ec;
    if (fs::is_directory(shared, ec)) {
        for (const auto& e : fs::directory_iterator(shared))
            if (e.path().extension() == ".bsdf") sources.push_back(rgl::read(e.path().string()).brdf);
    } else {
        WARN("skipped real RGL files: " << shared << " is missing");
    }
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const auto& src : sources) {
        const fs::path p = dir.path / "rgl.brdfz";
        CHECK(container::write(p.string(), *src).lossless);
        const container::ReadResult r = container::read(p.string());
        CHECK(r.meta.representation == "rgl");
        const auto* back = dynamic_cast<const rgl::RglBrdf*>(r.brdf.get());
        REQUIRE(back);
        const rgl::Tensors &a = src->tensors(), &b = back->tensors();
        CHECK(a.phi_i == b.phi_i);
        CHECK((r.meta.min_reader_version == 4) == (a.phi_i.size() > 1));
        CHECK(a.theta_i == b.theta_i);
        CHECK(a.ndf.values == b.ndf.values);
        CHECK(a.sigma.values == b.sigma.values);
        CHECK(a.vndf.values == b.vndf.values);
        CHECK(a.rgb.values == b.rgb.values);
        CHECK(a.luminance.values == b.luminance.values);
        CHECK(a.jacobian == b.jacobian);
        for (int k = 0; k < 200; ++k) {
            const Vec3 wi = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Vec3 wo = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Rgb fa = src->eval(wi, wo), fb = back->eval(wi, wo);
            CHECK(std::memcmp(&fa, &fb, sizeof fa) == 0);
            const BrdfSample sa = src->sample(wo, 0.3, 0.6), sb = back->sample(wo, 0.3, 0.6);
            CHECK(std::memcmp(&sa.wi, &sb.wi, sizeof sa.wi) == 0);
            CHECK(sa.pdf == sb.pdf);
        }
    }
}

TEST_CASE("Analytic models round-trip through .brdfz bit for bit", "[container][analytic][qemu]") {
    test::TempDir dir;
    const fs::path p = dir.path / "model.brdfz";
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const char* text : {"lambert+ggx", "lambert+ggx+ggx", "lafortune3", "ashikhmin_shirley"}) {
        const Model model = Model::parse(text);
        std::vector<double> params = model.defaults();
        params[0] *= 0.731;  // a value that is not a default
        const AnalyticBrdf source(model, params);
        CHECK(container::write(p.string(), source).lossless);
        const container::ReadResult r = container::read(p.string());
        CHECK(r.meta.representation == "analytic");
        CHECK(r.meta.features == std::vector<container::Feature>{{"core", 1}, {"analytic", 1}});
        const auto* back = dynamic_cast<const AnalyticBrdf*>(r.brdf.get());
        REQUIRE(back);
        CHECK(back->model().text() == text);
        CHECK(std::vector<double>(back->params().begin(), back->params().end()) == params);
        for (int k = 0; k < 100; ++k) {
            const Vec3 wi = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Vec3 wo = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Rgb fa = source.eval(wi, wo), fb = back->eval(wi, wo);
            CHECK(std::memcmp(&fa, &fb, sizeof fa) == 0);
        }
    }

    // A model from a newer brdfz (a lobe family this one does not know) is refused by name.
    {
        const std::string display = p.string();
        container::h5::Writer w(display);
        {
            container::h5::WriteNode root = w.root();
            const std::vector<std::string> features{"core", "analytic"};
            const std::vector<std::uint64_t> since{1, 1};
            root.attr("format", std::string("brdfz"));
            root.attr("version", std::uint64_t{1});
            root.attr("min_reader_version", std::uint64_t{1});
            root.attr("features", std::span<const std::string>(features));
            root.attr("feature_versions", std::span<const std::uint64_t>(since));
            for (const char* a : {"library_version", "created", "source_file", "source_format", "source_sha256"})
                root.attr(a, std::string("x"));
            root.attr("units", std::string(container::detail::kUnits));
            root.attr("cosine", std::string(container::detail::kCosine));
            root.attr("conventions", std::string(container::detail::kConventions));
            container::h5::WriteNode ach = root.group("achieved");
            ach.attr("lossless", std::uint64_t{1});
            ach.attr("nbytes", std::uint64_t{8});
            const std::vector<std::uint64_t> counts(6, 0);
            ach.attr("counts", std::span<const std::uint64_t>(counts));
            container::h5::WriteNode rep = root.group("representation");
            rep.attr("type", std::string("analytic"));
            rep.attr("spec", std::string("x"));
            rep.attr("model", std::string("lambert+sheen_from_the_future"));
            const std::vector<std::string> names{"a"};
            rep.attr("param_names", std::span<const std::string>(names));
            const double v = 1.0;
            rep.dataset("params", container::h5::DType::F64, {1}, &v);
        }
        w.close();
    }
    CHECK_THROWS_AS(container::read(p.string()), UnsupportedError);
    CHECK_THAT(read_error(p), Catch::Contains("lambert+sheen_from_the_future"));
}

TEST_CASE("A flipped byte anywhere is detected, and in a dataset the dataset is named", "[container][corrupt][qemu]") {
    test::TempDir dir;
    const fs::path good = dir.path / "good.brdfz", bad = dir.path / "bad.brdfz";
    container::write(good.string(), rgl::RglBrdf(small_tensors()));
    const std::vector<unsigned char> bytes = slurp(good);
    const auto extents = extents_of(bytes);
    REQUIRE(extents.size() == 6);  // theta_i, ndf, sigma, vndf, rgb, luminance

    // Each dataset: a flipped byte at its start, middle and end names it.
    std::vector<std::string> named;
    for (const auto& [off, len] : extents) {
        for (std::uint64_t at : {off, off + len / 2, off + len - 1}) {
            std::vector<unsigned char> b = bytes;
            b[at] ^= 0x10;
            spit(bad, b);
            const std::string msg = read_error(bad);
            INFO("byte " << at << ": " << msg);
            CHECK(msg.find("dataset /representation/") != std::string::npos);
            CHECK(msg.find("is corrupt") != std::string::npos);
            if (at == off) named.push_back(msg.substr(msg.find("/representation/"), msg.find(" is corrupt") - msg.find("/representation/")));
        }
    }
    std::sort(named.begin(), named.end());
    CHECK(named == std::vector<std::string>{"/representation/luminance", "/representation/ndf",
                                            "/representation/rgb", "/representation/sigma",
                                            "/representation/theta_i", "/representation/vndf"});

    // Every byte outside the datasets (header, HDF5 structure): the read fails with a FormatError
    // (or UnsupportedError for a header version), never succeeds, never crashes.
    std::size_t checked = 0;
    for (std::size_t at = 0; at < bytes.size(); ++at) {
        if (std::any_of(extents.begin(), extents.end(), [&](const auto& e) { return at >= e.first && at < e.first + e.second; }))
            continue;
        std::vector<unsigned char> b = bytes;
        b[at] ^= 0x01;
        spit(bad, b);
        bool failed = false;
        try {
            container::read(bad.string());
        } catch (const FormatError&) {
            failed = true;
        } catch (const UnsupportedError&) {
            failed = true;
        }
        INFO("byte " << at);
        CHECK(failed);
        ++checked;
    }
    CHECK(checked > 4096);
}

TEST_CASE("Truncated, oversized and foreign files are refused with a reason", "[container][corrupt][qemu]") {
    test::TempDir dir;
    const fs::path good = dir.path / "good.brdfz", bad = dir.path / "bad.brdfz";
    container::write(good.string(), TabularBrdf(random_table({5, 5, 5}, 1)));
    const std::vector<unsigned char> bytes = slurp(good);
    for (std::size_t n : {std::size_t{0}, std::size_t{7}, std::size_t{100}, std::size_t{4096}, bytes.size() / 2,
                          bytes.size() - 1}) {
        spit(bad, std::vector<unsigned char>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n)));
        INFO(n << " bytes");
        CHECK_THROWS_AS(container::read(bad.string()), FormatError);
    }
    std::vector<unsigned char> longer = bytes;
    longer.push_back(0);
    spit(bad, longer);
    CHECK_THAT(read_error(bad), Catch::Contains("oversized"));

    const fs::path merl_file = dir.path / "t.binary";
    merl::write(merl_file.string(), random_table({2, 2, 2}, 1));
    CHECK_THAT(read_error(merl_file), Catch::Contains("not a .brdfz container"));
    CHECK_THROWS_AS(container::read((dir.path / "missing.brdfz").string()), IoError);
    CHECK_THROWS_AS(container::write((dir.path / "no" / "such" / "dir.brdfz").string(), TabularBrdf(random_table({2, 2, 2}, 1))),
                    IoError);
    CHECK(!fs::exists(dir.path / "no"));
}

TEST_CASE("Files needing unknown features are refused, naming the feature", "[container][version]") {
    test::TempDir dir;
    // A file from a future writer: a valid container whose feature list names a feature (and version)
    // this reader does not know, built with the container's own low-level writer.
    const auto future = [&](const std::vector<std::string>& features, const std::vector<std::uint64_t>& since,
                            std::uint64_t min_reader) {
        const fs::path p = dir.path / "future.brdfz";
        const std::string display = p.string();
        container::h5::Writer w(display);
        {
            container::h5::WriteNode root = w.root();
            root.attr("format", std::string("brdfz"));
            root.attr("version", std::uint64_t{container::kVersion + 1});
            root.attr("min_reader_version", min_reader);
            root.attr("features", std::span<const std::string>(features));
            root.attr("feature_versions", std::span<const std::uint64_t>(since));
        }
        w.close();
        return p;
    };
    const std::uint64_t next = container::kVersion + 1;
    const fs::path p = future({"core", "hologram"}, {1, next}, next);
    const std::string msg = read_error(p);
    CHECK_THROWS_AS(container::read(p.string()), UnsupportedError);
    CHECK_THAT(msg, Catch::Contains("needs container feature 'hologram' (container version " + std::to_string(next) + ")"));
    CHECK_THAT(msg, Catch::Contains("tabular"));
    CHECK_THROWS_AS(container::read_metadata(p.string()), UnsupportedError);

    // Known features but a newer minimum reader version.
    CHECK_THAT(read_error(future({"core"}, {1}, next)),
               Catch::Contains("needs a reader of container version " + std::to_string(next)));

    // An HDF5 attribute edited in place and the header resealed: the reader still catches it by
    // its own checks (a feature list whose lengths disagree).
    const fs::path q = dir.path / "edited.brdfz";
    container::write(q.string(), TabularBrdf(random_table({3, 3, 3}, 2)));
    {
        container::h5::Quiet quiet;
        const hid_t f = H5Fopen(q.string().c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        REQUIRE(f >= 0);
        H5Adelete(f, "feature_versions");
        const hid_t space = H5Screate(H5S_SCALAR);
        const hid_t a = H5Acreate2(f, "feature_versions", H5T_STD_U64LE, space, H5P_DEFAULT, H5P_DEFAULT);
        H5Aclose(a);
        H5Sclose(space);
        H5Fclose(f);
    }
    reseal(q);
    CHECK_THAT(read_error(q), Catch::Contains("feature_versions"));
}

TEST_CASE("float16 factors cannot be misread as float32 ones", "[container][factored][f16]") {
    test::TempDir dir;
    Factors f;
    f.grid = {3, 2, 4};
    f.rank = 1;
    f.colour = FactorColour::Shared;
    f.dtype = FactorDtype::F16;
    f.u = {0.5f, 1.0f, 0.25f};
    f.v = {1.0f, 0.5f, 0.75f, 1.0f, 0.125f, 1.0f, 0.5f, 1.0f};
    f.colour_weights = {1.0f, 2.0f, 3.0f};
    const fs::path p = dir.path / "h.brdfz";
    container::write(p.string(), FactoredBrdf(f));
    CHECK(container::read(p.string()).meta.features.back() == container::Feature{"factored.float16", 2});
    // A float32-only reading of it: the element type attribute rewritten to say float32, the datasets
    // stay float16. Their type is checked, not trusted: refused, naming the dataset.
    {
        container::h5::Quiet quiet;
        const hid_t file = H5Fopen(p.string().c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        REQUIRE(file >= 0);
        const hid_t group = H5Gopen2(file, "representation", H5P_DEFAULT);
        REQUIRE(group >= 0);
        REQUIRE(H5Adelete(group, "dtype") >= 0);
        const hid_t t = H5Tcopy(H5T_C_S1);
        H5Tset_size(t, 7);
        H5Tset_strpad(t, H5T_STR_NULLPAD);
        const hid_t space = H5Screate(H5S_SCALAR);
        const hid_t a = H5Acreate2(group, "dtype", t, space, H5P_DEFAULT, H5P_DEFAULT);
        REQUIRE(a >= 0);
        REQUIRE(H5Awrite(a, t, "float32") >= 0);
        H5Aclose(a);
        H5Sclose(space);
        H5Tclose(t);
        H5Gclose(group);
        H5Fclose(file);
    }
    reseal(p);
    CHECK_THAT(read_error(p), Catch::Contains("dataset 'u' is not a float32 array"));
}

TEST_CASE("Tables with a φh axis round-trip through .brdfz bit for bit", "[container][phih]") {
    test::TempDir dir;
    const AnalyticBrdf source("lambert+ggx_aniso", {0.3, 0.2, 0.1, 1, 1, 1, 0.15, 0.4, 0.5});
    for (const char* spec : {"tabular:res=8x4x8,phih=4,symmetry=none", "tabular:res=8x4x8,phih=3,symmetry=bilateral",
                             "tabular:res=8x4x8,phih=4,symmetry=reciprocal,dtype=f16",
                             "tabular:res=8x4x8,phih=2,symmetry=none,dtype=u8log",
                             "svd:rank=2,res=8x4x8,phih=3,symmetry=none", "nmf:rank=2,res=8x4x8,phih=2,symmetry=bilateral"}) {
        INFO(spec);
        const Compressed c = compress(source, spec);
        const fs::path p = dir.path / "stack.brdfz";
        const container::Achieved a = container::write(p.string(), *c.brdf);
        CHECK(a.lossless);
        const container::ReadResult r = container::read(p.string());
        CHECK(r.meta.representation == "phi_h");
        CHECK(r.meta.min_reader_version == 4);
        const auto* back = dynamic_cast<const PhiHBrdf*>(r.brdf.get());
        REQUIRE(back);
        const auto& orig = dynamic_cast<const PhiHBrdf&>(*c.brdf);
        CHECK(back->symmetry() == orig.symmetry());
        CHECK(back->slices().size() == orig.slices().size());
        CHECK(back->nbytes() == orig.nbytes());
        std::mt19937_64 rng(13);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (int k = 0; k < 300; ++k) {
            const Vec3 wi = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Vec3 wo = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 0.01});
            const Rgb fa = c.brdf->eval(wi, wo), fb = back->eval(wi, wo);
            CHECK(std::memcmp(&fa, &fb, sizeof fa) == 0);
        }
    }
    // A table without φh is written and read as before (no phi-h feature, its own reader version).
    const Compressed flat = compress(source, "tabular:res=8x4x8");
    const fs::path q = dir.path / "flat.brdfz";
    container::write(q.string(), *flat.brdf);
    const container::ReadResult r = container::read(q.string());
    CHECK(r.meta.representation == "tabular");
    CHECK(r.meta.min_reader_version == 1);
    CHECK(dynamic_cast<const TabularBrdf*>(r.brdf.get()));
}
