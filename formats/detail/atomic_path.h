// Write-then-rename for writers that open the output by name themselves (HDF5, OpenEXR), the
// path-yielding sibling of lib/src/detail/atomic_file.h: a NAME.tmp-XXXXXX beside NAME is created
// for the library to overwrite, and replaces NAME only in commit(). A failed or thrown-through write
// removes the temporary, so no file appears at NAME (and no temporary either, except after SIGKILL).
#pragma once

#include <string>

namespace brdfz::detail {

class AtomicPath {
public:
    explicit AtomicPath(std::string path);  // IoError if the temporary cannot be created
    ~AtomicPath();
    AtomicPath(const AtomicPath&) = delete;
    AtomicPath& operator=(const AtomicPath&) = delete;

    const std::string& path() const { return path_; }
    const std::string& tmp_path() const { return tmp_path_; }  // where the library writes

    // The library must have closed the temporary: fsync it, make it readable (0644) and rename it onto
    // path(). IoError otherwise.
    void commit();

private:
    std::string path_, tmp_path_;
    bool committed_ = false;
};

}  // namespace brdfz::detail
