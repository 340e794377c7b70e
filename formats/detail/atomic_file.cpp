#include "detail/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <random>

#include "brdfz/errors.h"
#include "brdfz/formats/io.h"

namespace brdfz::detail {
namespace {

constexpr char kTmpTag[] = ".tmp-";
constexpr std::size_t kSuffix = 6;  // random characters after the tag, as mkstemp's XXXXXX

std::string random_suffix() {
    static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    std::random_device rd;
    std::uint64_t r = (std::uint64_t{rd()} << 32) ^ rd();
    std::string s;
    for (std::size_t k = 0; k < kSuffix; ++k, r /= 62) s += kChars[r % 62];
    return s;
}

bool is_temporary_of(const std::string& name, const std::string& prefix) {
    if (name.size() != prefix.size() + kSuffix || name.compare(0, prefix.size(), prefix) != 0) return false;
    for (std::size_t k = prefix.size(); k < name.size(); ++k)
        if (!std::isalnum(static_cast<unsigned char>(name[k]))) return false;
    return true;
}

std::string folder_of(const std::string& path) {
    const std::string dir = std::filesystem::path(path).parent_path().string();
    return dir.empty() ? "." : dir;
}

[[noreturn]] void fail(const std::string& path, const std::string& what, int err) {
    throw IoError(path, what + ": " + std::strerror(err));
}

// What a file that is not a regular one is, for the refusal.
std::string kind_of(mode_t mode) {
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISSOCK(mode)) return "a socket";
    return "something else";
}

// IoError naming `path` unless `target` is missing or a regular file: a write renames a new file onto
// its name, which would replace a device, a FIFO or a folder with a regular file.
void check_replaceable(const std::string& path, const std::string& target) {
    struct stat st {};
    if (::lstat(target.c_str(), &st) != 0) {
        if (errno == ENOENT) return;
        fail(path, "cannot write", errno);
    }
    if (!S_ISREG(st.st_mode))
        throw IoError(path, (target == path ? "" : "links to " + target + ", which ") + "is " + kind_of(st.st_mode) +
                                "; only regular files are written");
}

// Where the bytes of `path` go: a symbolic link to a regular file is written through (its target
// replaced, the link kept), as a shell's redirection writes through it; a link to nothing or to
// anything but a regular file is refused.
std::string write_target(const std::string& path) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) {
        check_replaceable(path, path);
        return path;
    }
    if (::stat(path.c_str(), &st) != 0)
        throw IoError(path, "is a symbolic link to a missing file; only regular files are written");
    std::error_code ec;
    const std::filesystem::path target = std::filesystem::canonical(path, ec);
    if (!ec) {
        check_replaceable(path, target.string());
        return target.string();
    }
    // Links of /proc (/dev/stdout) may lead to what has no name: a pipe, a deleted file.
    throw IoError(path, std::string("links to ") +
                            (S_ISFIFO(st.st_mode) ? "a pipe" : S_ISREG(st.st_mode) ? "a file without a name" : kind_of(st.st_mode)) +
                            "; only regular files are written");
}

}  // namespace

int remove_stale_temporaries(const std::string& path) {
    const std::string dir = folder_of(path);
    const std::string prefix = std::filesystem::path(path).filename().string() + kTmpTag;
    DIR* d = ::opendir(dir.c_str());
    if (!d) return 0;
    int removed = 0;
    while (const dirent* e = ::readdir(d)) {
        if (!is_temporary_of(e->d_name, prefix)) continue;
        const std::string full = dir + "/" + e->d_name;
        const int fd = ::open(full.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0) continue;
        // Unlocked: its writer is gone (a lock lives as long as the writer's descriptor). The name
        // must still be this file when it is removed.
        struct stat held {}, named {};
        if (::fstat(fd, &held) == 0 && S_ISREG(held.st_mode) && held.st_uid == ::geteuid() &&
            ::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::lstat(full.c_str(), &named) == 0 && named.st_ino == held.st_ino &&
            named.st_dev == held.st_dev && ::unlink(full.c_str()) == 0)
            ++removed;
        ::close(fd);
    }
    ::closedir(d);
    return removed;
}

AtomicFile::AtomicFile(std::string path, Temporary kind)
    : path_(std::move(path)), target_(write_target(path_)), dir_(folder_of(target_)) {
    remove_stale_temporaries(target_);
    if (kind == Temporary::Unnamed) {
        fd_ = ::open(dir_.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0666);
        // Libraries reopen it, and commit() links it, through /proc's name of the descriptor.
        if (fd_ >= 0) {
            open_path_ = "/proc/self/fd/" + std::to_string(fd_);
            if (::access(open_path_.c_str(), F_OK) != 0) {
                ::close(fd_);
                fd_ = -1;
            }
        }
        // Held while it is linked under a temporary name in commit(), so that no cleaner removes it.
        if (fd_ >= 0 && ::flock(fd_, LOCK_EX) != 0) {
            const int err = errno;
            ::close(fd_);
            fail(path_, "cannot lock the temporary file", err);
        }
    }
    if (fd_ < 0) open_named();
}

void AtomicFile::open_named() {
    for (int attempt = 0; attempt < 100; ++attempt) {
        const std::string name = target_ + kTmpTag + random_suffix();
        const int fd = ::open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0) {
            if (errno == EEXIST) continue;
            fail(path_, "cannot create temporary file", errno);
        }
        // A cleaner may have taken it between open and flock: then it is (being) removed.
        struct stat st {};
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0 || ::fstat(fd, &st) != 0 || st.st_nlink == 0) {
            ::close(fd);
            continue;
        }
        fd_ = fd;
        tmp_path_ = open_path_ = name;
        return;
    }
    throw IoError(path_, "cannot create a temporary file beside it");
}

AtomicFile::~AtomicFile() {
    if (stream_) std::fclose(stream_);
    if (!committed_ && !tmp_path_.empty()) ::unlink(tmp_path_.c_str());
    if (fd_ >= 0) ::close(fd_);
}

void AtomicFile::write(const void* data, std::size_t bytes) {
    if (!stream_) {
        // A second descriptor of the same open file (shared offset and lock), so fclose leaves fd_.
        const int fd = ::dup(fd_);
        if (fd < 0 || !(stream_ = ::fdopen(fd, "wb"))) {
            const int err = errno;
            if (fd >= 0) ::close(fd);
            fail(path_, "cannot write", err);
        }
    }
    if (std::fwrite(data, 1, bytes, stream_) != bytes) fail(path_, "write failed", errno);
}

void AtomicFile::commit() {
    if (stream_) {
        const bool flushed = std::fflush(stream_) == 0;
        const int err = errno;
        std::fclose(stream_);
        stream_ = nullptr;
        if (!flushed) fail(path_, "cannot complete write", err);
    }
    if (::fsync(fd_) != 0) fail(path_, "cannot complete write", errno);
    // Again: what is at the name now is what the rename replaces.
    check_replaceable(path_, target_);
    struct stat old {};
    if (::lstat(target_.c_str(), &old) == 0 && ::fchmod(fd_, old.st_mode & 07777) != 0)
        fail(path_, "cannot keep the replaced file's mode", errno);
    if (unnamed()) {
        // Linked straight in when NAME is new; over an existing NAME, linked beside it and renamed.
        if (::linkat(AT_FDCWD, open_path_.c_str(), AT_FDCWD, target_.c_str(), AT_SYMLINK_FOLLOW) != 0) {
            if (errno != EEXIST) fail(path_, "cannot complete write", errno);
            std::string name;
            int linked = -1;
            for (int attempt = 0; attempt < 100 && linked != 0; ++attempt) {
                name = target_ + kTmpTag + random_suffix();
                linked = ::linkat(AT_FDCWD, open_path_.c_str(), AT_FDCWD, name.c_str(), AT_SYMLINK_FOLLOW);
                if (linked != 0 && errno != EEXIST) fail(path_, "cannot complete write", errno);
            }
            if (linked != 0) throw IoError(path_, "cannot complete write: no free temporary name");
            if (std::rename(name.c_str(), target_.c_str()) != 0) {
                const int err = errno;
                ::unlink(name.c_str());
                fail(path_, "cannot complete write", err);
            }
        }
    } else if (std::rename(tmp_path_.c_str(), target_.c_str()) != 0) {
        fail(path_, "cannot complete write", errno);
    }
    committed_ = true;
    // The new name itself survives a crash once the folder is synced; the data already are.
    const int dir = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
        ::fsync(dir);
        ::close(dir);
    }
}

}  // namespace brdfz::detail

namespace brdfz {

void check_output(const std::string& path) { detail::write_target(path); }

}  // namespace brdfz
