// Output files: killed writes leave nothing behind, modes follow the umask or the replaced file, and
// two writes of the same content are the same bytes.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "brdfz/formats/merl.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"
#include "container/h5.h"
#include "detail/atomic_file.h"
#include "test_util.h"

using namespace brdfz;
using detail::AtomicFile;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> entries(const fs::path& dir) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

unsigned mode_of(const fs::path& p) {
    struct stat st {};
    REQUIRE(::stat(p.c_str(), &st) == 0);
    return st.st_mode & 07777;
}

// Runs body() in a child process that kills itself with SIGKILL mid-write; waits for it.
template <typename Body>
void killed_child(Body body) {
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        body();
        ::_exit(0);  // body() did not kill: seen as a failure below
    }
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    REQUIRE(WIFSIGNALED(status));
    REQUIRE(WTERMSIG(status) == SIGKILL);
}

struct Umask {
    explicit Umask(mode_t m) : old(::umask(m)) {}
    ~Umask() { ::umask(old); }
    mode_t old;
};

TabularBrdf small_table() {
    TabulateOptions o;
    o.grid = GridSpec{8, 8, 16};
    return TabularBrdf(tabulate(AnalyticBrdf("lambert", {0.2, 0.3, 0.4}), o).table);
}

}  // namespace

TEST_CASE("robustness: a write killed with SIGKILL leaves no file and no temporary", "[robustness][files]") {
    const test::TempDir dir;
    if (!AtomicFile((dir.path / "probe").string()).unnamed()) {
        WARN("skipped: " << dir.path << " has no O_TMPFILE (the next test covers the fallback)");
        return;
    }
    const fs::path out = dir.path / "OUT.binary";
    killed_child([&] {
        AtomicFile f(out.string());
        f.write("partial", 7);
        ::kill(::getpid(), SIGKILL);
    });
    CHECK(entries(dir.path).empty());

    // A library that opens the file by name (OpenEXR) writes through the same unnamed file.
    killed_child([&] {
        AtomicFile f((dir.path / "OUT.exr").string());
        std::ofstream(f.open_path(), std::ios::binary) << "partial";
        ::kill(::getpid(), SIGKILL);
    });
    CHECK(entries(dir.path).empty());

    // Killed while replacing: the old file is intact.
    merl::write(out.string(), small_table().table());
    const auto before = fs::file_size(out);
    killed_child([&] {
        AtomicFile f(out.string());
        f.write("partial", 7);
        ::kill(::getpid(), SIGKILL);
    });
    CHECK(entries(dir.path) == std::vector<std::string>{"OUT.binary"});
    CHECK(fs::file_size(out) == before);
}

TEST_CASE("robustness: without O_TMPFILE, the next write removes what a killed one left", "[robustness][files]") {
    const test::TempDir dir;
    const fs::path out = dir.path / "OUT.brdfz";
    killed_child([&] {
        AtomicFile f(out.string(), AtomicFile::Temporary::Named);
        std::ofstream(f.open_path(), std::ios::binary) << "partial";
        ::kill(::getpid(), SIGKILL);
    });
    const std::vector<std::string> left = entries(dir.path);
    REQUIRE(left.size() == 1);
    CHECK(left[0].rfind("OUT.brdfz.tmp-", 0) == 0);
    CHECK(left[0].size() == std::string("OUT.brdfz.tmp-XXXXXX").size());

    // A temporary of another output, a file that only looks like one, and a live writer's are kept.
    std::ofstream(dir.path / "OTHER.brdfz.tmp-abcdef") << "x";
    std::ofstream(dir.path / "OUT.brdfz.tmp-notes.txt") << "x";
    AtomicFile live(out.string(), AtomicFile::Temporary::Named);
    live.write("live", 4);
    container::write(out.string(), small_table());
    std::vector<std::string> kept{"OTHER.brdfz.tmp-abcdef", "OUT.brdfz", "OUT.brdfz.tmp-notes.txt",
                                  fs::path(live.open_path()).filename().string()};
    std::sort(kept.begin(), kept.end());
    CHECK(entries(dir.path) == kept);
    CHECK(container::read(out.string()).brdf);
    live.commit();  // the live writer finishes unharmed
    CHECK(fs::file_size(out) == 4);
    CHECK(detail::remove_stale_temporaries(out.string()) == 0);
}

TEST_CASE("robustness: new files follow the umask, a replaced file keeps its mode", "[robustness][files]") {
    const test::TempDir dir;
    for (AtomicFile::Temporary kind : {AtomicFile::Temporary::Unnamed, AtomicFile::Temporary::Named}) {
        const fs::path p = dir.path / (kind == AtomicFile::Temporary::Named ? "named.binary" : "unnamed.binary");
        {
            const Umask mask(027);
            AtomicFile f(p.string(), kind);
            f.write("x", 1);
            f.commit();
        }
        CHECK(mode_of(p) == 0640);
        REQUIRE(::chmod(p.c_str(), 0600) == 0);
        {
            const Umask mask(022);
            AtomicFile f(p.string(), kind);
            f.write("y", 1);
            f.commit();
        }
        CHECK(mode_of(p) == 0600);
    }
    // Every writer goes through it: the container and OpenEXR writers, which open by name, too.
    for (const char* name : {"t.brdfz", "t.exr", "t.binary", "t.bsdf"}) {
        INFO(name);
        const fs::path p = dir.path / name;
        {
            const Umask mask(077);
            save(small_table(), p.string());
        }
        CHECK(mode_of(p) == 0600);
        REQUIRE(::chmod(p.c_str(), 0640) == 0);
        save(small_table(), p.string());
        CHECK(mode_of(p) == 0640);
    }
}

TEST_CASE("robustness: .brdfz bytes are reproducible with SOURCE_DATE_EPOCH, no HDF5 object times",
          "[robustness][files][container]") {
    const test::TempDir dir;
    const TabularBrdf t = small_table();
    const auto bytes = [](const fs::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    ::setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    container::write((dir.path / "a.brdfz").string(), t);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // HDF5 stores object times in seconds
    container::write((dir.path / "b.brdfz").string(), t);
    CHECK(container::read_metadata((dir.path / "a.brdfz").string()).created == "2023-11-14T22:13:20Z");
    CHECK(bytes(dir.path / "a.brdfz") == bytes(dir.path / "b.brdfz"));
    ::setenv("SOURCE_DATE_EPOCH", "soon", 1);
    CHECK_THROWS_WITH(container::write((dir.path / "c.brdfz").string(), t), Catch::Contains("SOURCE_DATE_EPOCH='soon'"));
    CHECK_FALSE(fs::exists(dir.path / "c.brdfz"));
    ::unsetenv("SOURCE_DATE_EPOCH");

    container::write((dir.path / "d.brdfz").string(), t);
    const container::h5::Quiet quiet;
    const hid_t f = H5Fopen((dir.path / "d.brdfz").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    REQUIRE(f >= 0);
    for (const char* object : {"/", "/representation", "/representation/values", "/achieved"}) {
        INFO(object);
        H5O_info_t info{};
        REQUIRE(H5Oget_info_by_name2(f, object, &info, H5O_INFO_TIME, H5P_DEFAULT) >= 0);
        CHECK(info.ctime == 0);
        CHECK(info.mtime == 0);
    }
    H5Fclose(f);
}

TEST_CASE("robustness: a PCA material whose basis file has gone is saved with the basis embedded",
          "[robustness][files][pca]") {
    const test::TempDir dir;
    std::vector<Table> tables;
    for (double alpha : {0.1, 0.2, 0.4}) {
        TabulateOptions o;
        o.grid = GridSpec{4, 4, 8};
        tables.push_back(tabulate(AnalyticBrdf("lambert+ggx", {0.3, 0.4, 0.5, 0.5, 0.5, 0.5, alpha, 0.04}), o).table);
    }
    const std::vector<const Table*> ptrs{&tables[0], &tables[1], &tables[2]};
    PcaTrainOptions o;
    o.k_max = 2;
    const fs::path basis_file = dir.path / "basis.brdfz", material = dir.path / "m.brdfz";
    const auto basis = container::write_pca_basis(basis_file.string(), train_pca_basis(ptrs, o));
    const PcaBrdf referenced(basis, basis->project(tables[1], 2), Lookup::Linear, PcaBrdf::BasisStorage::Referenced);
    const Vec3 wi = normalize(Vec3{0.3, 0.1, 0.9}), wo = normalize(Vec3{-0.2, 0.4, 0.8});

    // While the basis file holds it, the material refers to it (and is small).
    container::write(material.string(), referenced);
    CHECK(container::read_metadata(material.string()).datasets.size() == 1);  // the coefficients only
    const auto small = fs::file_size(material);

    // Deleted, or replaced by another basis: the material carries its basis and reads back as itself.
    for (const bool replace : {false, true}) {
        INFO((replace ? "replaced" : "deleted"));
        fs::remove(basis_file);
        if (replace) {
            PcaTrainOptions fewer = o;
            fewer.k_max = 1;
            container::write_pca_basis(basis_file.string(), train_pca_basis(ptrs, fewer));
        }
        container::write(material.string(), referenced);
        CHECK(fs::file_size(material) > small);
        const auto back = load(material.string()).brdf;
        CHECK(dynamic_cast<const PcaBrdf&>(*back).basis_storage() == PcaBrdf::BasisStorage::Embedded);
        CHECK(back->eval(wi, wo) == referenced.eval(wi, wo));
    }
}
