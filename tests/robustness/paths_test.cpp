// Paths that are not regular files: an output that is a FIFO, a device, a folder or a link to one is
// refused and left as it was; a link to a regular file is written through; standard input, pipes and
// devices are not read. Devices are made in a temporary folder, never the machine's /dev.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/model.h"
#include "detail/atomic_file.h"
#include "test_util.h"

using namespace brdfz;
using detail::AtomicFile;
namespace fs = std::filesystem;

namespace {

const AnalyticBrdf& material() {
    static const AnalyticBrdf m("lambert", {0.3, 0.4, 0.5});
    return m;
}

SaveOptions small_grid() {
    SaveOptions o;
    o.grid = GridSpec{4, 4, 8};
    return o;
}

std::vector<std::string> entries(const fs::path& dir) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

std::string save_error(const fs::path& p) {
    try {
        save(material(), p.string(), small_grid());
    } catch (const IoError& e) {
        return e.what();
    }
    return "saved";
}

mode_t type_of(const fs::path& p) {
    struct stat st {};
    REQUIRE(::lstat(p.c_str(), &st) == 0);
    return st.st_mode & S_IFMT;
}

}  // namespace

TEST_CASE("robustness: an output that is a FIFO, a device, a folder or a link to one is refused and left as it is",
          "[robustness][files]") {
    const test::TempDir dir;
    const fs::path fifo = dir.path / "fifo.binary";
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    CHECK(save_error(fifo) == fifo.string() + ": is a FIFO; only regular files are written");
    CHECK(type_of(fifo) == S_IFIFO);

    const fs::path folder = dir.path / "folder.brdfz";
    fs::create_directory(folder);
    CHECK(save_error(folder) == folder.string() + ": is a folder; only regular files are written");

    const fs::path to_fifo = dir.path / "to_fifo.exr";
    fs::create_symlink(fifo, to_fifo);
    CHECK(save_error(to_fifo) == to_fifo.string() + ": links to " + fifo.string() +
                                     ", which is a FIFO; only regular files are written");
    CHECK(type_of(to_fifo) == S_IFLNK);

    const fs::path dangling = dir.path / "dangling.npy";
    fs::create_symlink(dir.path / "missing.npy", dangling);
    CHECK_THAT(save_error(dangling), Catch::StartsWith(dangling.string() + ": is a symbolic link to a missing file"));
    CHECK(type_of(dangling) == S_IFLNK);

    // /dev/null's numbers, in the temporary folder (mknod needs CAP_MKNOD: root, outside most sandboxes).
    const fs::path device = dir.path / "null.bsdf";
    if (::mknod(device.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0) {
        CHECK(save_error(device) == device.string() + ": is a device; only regular files are written");
        CHECK(type_of(device) == S_IFCHR);
    } else {
        WARN("mknod is not permitted here: the device case is left to a FIFO and links");
    }
    // Nothing else was made beside them: no temporary, no file at a link's missing target.
    std::vector<std::string> left = entries(dir.path);
    left.erase(std::remove(left.begin(), left.end(), "null.bsdf"), left.end());
    CHECK(left == std::vector<std::string>{"dangling.npy", "fifo.binary", "folder.brdfz", "to_fifo.exr"});
}

TEST_CASE("robustness: an output that is a link to a regular file is written through, keeping the link",
          "[robustness][files]") {
    const test::TempDir dir;
    fs::create_directories(dir.path / "data");
    fs::create_directories(dir.path / "links");
    for (AtomicFile::Temporary kind : {AtomicFile::Temporary::Unnamed, AtomicFile::Temporary::Named}) {
        const fs::path target = dir.path / "data" / "target.binary", link = dir.path / "links" / "out.binary";
        {
            AtomicFile old(target.string());
            old.write("old", 3);
            old.commit();
        }
        ::chmod(target.c_str(), 0600);
        fs::remove(link);
        fs::create_symlink("../data/target.binary", link);
        AtomicFile f(link.string(), kind);
        CHECK(f.path() == link.string());
        CHECK(f.target() == fs::canonical(target).string());
        f.write("new bytes", 9);
        f.commit();
        CHECK(type_of(link) == S_IFLNK);
        CHECK(fs::read_symlink(link) == "../data/target.binary");
        CHECK(fs::file_size(target) == 9);
        CHECK((fs::status(target).permissions() & fs::perms::all) == (fs::perms::owner_read | fs::perms::owner_write));
        CHECK(entries(dir.path / "data") == std::vector<std::string>{"target.binary"});
        CHECK(entries(dir.path / "links") == std::vector<std::string>{"out.binary"});
    }
    // A whole save through the link: the target reads back as the table written.
    const fs::path link = dir.path / "links" / "out.binary";
    save(material(), link.string(), small_grid());
    CHECK(type_of(link) == S_IFLNK);
    CHECK(load((dir.path / "data" / "target.binary").string()).info.dims == std::vector<std::size_t>{4, 4, 8});
}

TEST_CASE("robustness: standard input, pipes and devices are not read", "[robustness][files]") {
    const test::TempDir dir;
    const fs::path fifo = dir.path / "pipe";
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    for (const std::string& path : {std::string("-"), fifo.string()}) {
        CHECK_THROWS_AS(load(path), UnsupportedError);
        CHECK_THROWS_WITH(load(path), path + ": standard input, pipes and devices are not read: give a file's name");
        CHECK_THROWS_WITH(detect_format(path), Catch::Contains("standard input, pipes and devices are not read"));
    }
}
