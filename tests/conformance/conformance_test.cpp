// Every representation kind (one line each below) and every registered file format (all of them,
// from the registry) through the shared checks of checks.h.
#include <filesystem>
#include <fstream>

#include "brdfz/compress.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/formats/registry.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_svd.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/pca.h"
#include "brdfz/tabulate.h"
#include "checks.h"

namespace fs = std::filesystem;
using namespace brdfz;

namespace {

// An energy-conserving source with a lobe the grids resolve.
AnalyticBrdf source() { return AnalyticBrdf("lambert+ggx", {0.3, 0.25, 0.2, 0.6, 0.6, 0.6, 0.35, 0.04}); }

struct KindCase {
    const char* spec;
    bool reciprocal;
    bool rgl_source = false;  // built from an RGL file's tensors of the source (the kinds that need one)
};

// One line per representation kind and setting worth its own check. A pca spec names its basis as
// BASIS, replaced by a basis trained for the test.
const KindCase kKinds[] = {
    {"tabular:res=16x16x32", true},
    {"tabular:res=16x16x32,dtype=f16", true},
    {"tabular:res=16x16x32,dtype=u8log,lookup=nearest", true},
    {"bivariate:res=16x16,phi=8", true},
    {"bivariate:res=16x16,phi=8,dtype=f16,lookup=nearest", true},
    {"svd:rank=2,res=16x16x32", true},
    {"nmf:rank=2,res=16x16x32,iterations=20", true},
    {"pca:basis=BASIS,k=2", true},
    {"analytic:lambert+ggx,starts=1", true},
    {"analytic:lambert+ggx,starts=1,sampler=lobes", true},
    {"tabular:res=16x16x32,phih=4,symmetry=none", false},
    {"tabular:res=16x16x32,phih=4,symmetry=reciprocal,dtype=f16", true},
    {"tabular:res=16x16x32,phih=3,symmetry=bilateral,dtype=u8log", false},
    {"svd:rank=2,res=16x16x32,phih=3,symmetry=none", false},
    {"tabular:res=16x16x16,symmetry=bilateral", false},
    {"svd:rank=2,res=16x16x16,symmetry=bilateral,dtype=f16", false},
    {"tabular:res=16x16x32,dtype=f16,hwarp=auto", true},
    {"svd:rank=2,space=cos,res=16x16x32,hwarp=4", true},
    {"rgl_svd:rank=4", false, true},
    {"rgl_svd:rank=4,dtype=i8", false, true},
};

// The source as an RGL-EPFL file holds it (formats/rgl_writer.h), shaped as those files are.
const rgl::RglBrdf& rgl_source() {
    static const rgl::RglBrdf file = [] {
        rgl::WriteOptions shape;
        shape.n_theta_i = 8;
        shape.rgb_resolution = 32;
        rgl::Tensors t = rgl::derive(source(), shape);
        t.vndf = rgl::derived_vndf(t.theta_i, t.ndf, t.vndf.rows, t.vndf.cols);  // a measurement's (rgl_svd.h)
        return rgl::RglBrdf(std::move(t));
    }();
    return file;
}

// A basis from a few variations of the source, written where the pca line can name it.
std::string pca_basis(const fs::path& dir) {
    std::vector<Table> tables;
    for (double alpha : {0.2, 0.35, 0.5, 0.7}) {
        TabulateOptions t;
        t.grid = GridSpec{16, 16, 32};
        tables.push_back(tabulate(AnalyticBrdf("lambert+ggx", {0.3, 0.25, 0.2, 0.6, 0.6, 0.6, alpha, 0.04}), t).table);
    }
    std::vector<const Table*> pointers;
    for (const Table& t : tables) pointers.push_back(&t);
    const std::string path = (dir / "basis.brdfz").string();
    container::write_pca_basis(path, train_pca_basis(pointers));
    return path;
}

}  // namespace

TEST_CASE("conformance: every representation kind", "[conformance]") {
    test::TempDir dir;
    const std::string basis = pca_basis(dir.path);
    const CompressOptions files = with_file_access({});
    for (const KindCase& c : kKinds) {
        std::string spec = c.spec;
        if (const std::size_t at = spec.find("BASIS"); at != std::string::npos) spec.replace(at, 5, basis);
        SECTION(c.spec) {
            const AnalyticBrdf analytic = source();
            const Brdf& from = c.rgl_source ? static_cast<const Brdf&>(rgl_source()) : analytic;
            const Compressed built = compress(from, spec, files);
            const Brdf& b = *built.brdf;
            test::check_conventions(b);
            if (c.reciprocal) test::check_reciprocity(b);
            test::check_furnace(b, 1.0);
            test::check_sampler(b, 20000, test::kViewsLevel, {test::Draws::Batch, 16});
            test::check_batch_bits(b);
            LoadOptions reading;
            if (spec.find("lookup=nearest") != std::string::npos) reading.lookup = Lookup::Nearest;
            test::check_container_round_trip(b, reading);
            // A key the kind does not take is refused, not ignored.
            CHECK_THROWS_WITH(compress(from, spec + ",nosuchkey=1", files), Catch::Contains("unknown option(s) nosuchkey"));
        }
    }
    // Every registered kind has a line.
    for (const ReprKind& k : representation_kinds()) {
        bool listed = false;
        for (const KindCase& c : kKinds) listed = listed || std::string(c.spec).rfind(k.name + ":", 0) == 0;
        INFO("kind " << k.name << " has no line in kKinds");
        CHECK(listed);
    }
}

TEST_CASE("conformance: every declared key is read by its kind's builder", "[conformance][compress]") {
    // A declared key given its plain default is accepted (not "unknown"); reading an undeclared key
    // is a logic error the registry catches (spec.h), so the declarations and the builders agree.
    for (const ReprKind& k : representation_kinds()) {
        if (k.name == "pca") continue;  // needs a basis file: the kinds test covers its keys' use
        for (const SpecKey& key : k.keys) {
            if (key.default_value.find_first_of(" ()") != std::string::npos) continue;
            std::string spec = k.name + ":" + (k.positional.empty() ? "" : "lambert,");
            const std::string res = k.name == "bivariate" ? "8x8" : "8x8x16";
            spec += key.name + "=" + key.default_value + (key.name == "res" ? "" : ",res=" + res);
            if (k.name == "analytic") spec = "analytic:lambert," + key.name + "=" + key.default_value + ",starts=1";
            if (k.name == "rgl_svd") spec = "rgl_svd:" + key.name + "=" + key.default_value;
            INFO(spec);
            try {
                compress(source(), spec);
            } catch (const ValueError& e) {
                CHECK_THAT(e.what(), !Catch::Contains("unknown option"));
            }
        }
    }
}

TEST_CASE("conformance: every registered format", "[conformance][io][qemu]") {
    for (const Format& f : all_formats()) {
        SECTION(f.name) {
            test::TempDir dir;
            REQUIRE(f.examples);
            REQUIRE(!f.extensions.empty());
            f.examples(dir.path.string());
            std::vector<fs::path> examples;
            for (const auto& e : fs::directory_iterator(dir.path)) examples.push_back(e.path());
            REQUIRE(!examples.empty());
            for (const fs::path& p : examples) {
                INFO(p.filename().string());
                // The contents alone tell the format.
                const fs::path renamed = dir.path / (p.stem().string() + ".unknown");
                fs::copy_file(p, renamed);
                CHECK(detect_format(renamed.string()) == f.name);
                fs::remove(renamed);
                if (f.read_measurements) {
                    CHECK(holds_measurements(p.string()));
                    CHECK(!load_measurements(p.string()).set.samples.empty());
                    continue;
                }
                const Loaded loaded = load(p.string());
                CHECK(loaded.info.format == f.name);
                test::check_conventions(*loaded.brdf);
                if (f.write) {
                    // What the format read, it writes back as it was.
                    const fs::path again = dir.path / ("again" + f.extensions.front());
                    save(*loaded.brdf, again.string());
                    const Loaded back = load(again.string());
                    const auto [wi, wo] = test::random_pairs(300, 15);
                    for (std::size_t k = 0; k < wi.size(); ++k)
                        test::check_close(back.brdf->eval(wi[k], wo[k]), loaded.brdf->eval(wi[k], wo[k]), 1e-6);
                    fs::remove(again);
                }
            }
            // An empty file and a truncated one are refused with the library's errors, never a crash.
            const fs::path empty = dir.path / ("empty" + f.extensions.front());
            std::ofstream(empty).close();
            CHECK_THROWS_AS(f.read ? (void)f.read(empty.string(), {}) : (void)f.read_measurements(empty.string()), Error);
            const fs::path& first = examples.front();
            const fs::path cut = dir.path / ("cut" + f.extensions.front());
            fs::copy_file(first, cut);
            fs::resize_file(cut, fs::file_size(first) / 2);
            try {
                if (f.read) test::check_conventions(*f.read(cut.string(), {}).brdf);
                else f.read_measurements(cut.string());
            } catch (const Error&) {
            }
        }
    }
}
