#include "detail/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "brdfz/errors.h"

namespace brdfz::detail {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
    std::string tmpl = path_ + ".tmp-XXXXXX";
    const int fd = ::mkstemp(tmpl.data());
    if (fd < 0) throw IoError(path_, std::string("cannot create temporary file: ") + std::strerror(errno));
    tmp_path_ = tmpl;
    ::fchmod(fd, 0644);  // mkstemp creates 0600; output files are ordinary readable files
    file_ = ::fdopen(fd, "wb");
    if (!file_) {
        ::close(fd);
        ::unlink(tmp_path_.c_str());
        throw IoError(path_, "cannot open temporary file");
    }
}

AtomicFile::~AtomicFile() {
    if (file_) {
        std::fclose(file_);
        ::unlink(tmp_path_.c_str());
    }
}

void AtomicFile::write(const void* data, std::size_t bytes) {
    if (std::fwrite(data, 1, bytes, file_) != bytes)
        throw IoError(path_, std::string("write failed: ") + std::strerror(errno));
}

void AtomicFile::commit() {
    const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    const int err = errno;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!flushed || !closed || std::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
        const std::string reason = std::strerror(flushed ? errno : err);
        ::unlink(tmp_path_.c_str());
        throw IoError(path_, "cannot complete write: " + reason);
    }
}

}  // namespace brdfz::detail
