#include "atomic_path.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "brdfz/errors.h"

namespace brdfz::detail {

AtomicPath::AtomicPath(std::string path) : path_(std::move(path)) {
    std::string tmpl = path_ + ".tmp-XXXXXX";
    const int fd = ::mkstemp(tmpl.data());
    if (fd < 0) throw IoError(path_, std::string("cannot create temporary file: ") + std::strerror(errno));
    ::close(fd);  // the name is reserved; the library reopens and truncates it
    tmp_path_ = tmpl;
}

AtomicPath::~AtomicPath() {
    if (!committed_) ::unlink(tmp_path_.c_str());
}

void AtomicPath::commit() {
    const int fd = ::open(tmp_path_.c_str(), O_RDONLY);
    const bool synced = fd >= 0 && ::fsync(fd) == 0 && ::fchmod(fd, 0644) == 0;
    const int err = errno;
    if (fd >= 0) ::close(fd);
    if (!synced || std::rename(tmp_path_.c_str(), path_.c_str()) != 0)
        throw IoError(path_, std::string("cannot complete write: ") + std::strerror(synced ? errno : err));
    committed_ = true;
}

}  // namespace brdfz::detail
