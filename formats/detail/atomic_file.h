// Write-then-rename output file: bytes go to NAME.tmp-XXXXXX beside NAME, which replaces NAME only in
// commit(). A failed, thrown-through or killed write leaves no file at NAME (and no temporary either,
// except after SIGKILL).
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>

namespace brdfz::detail {

class AtomicFile {
public:
    explicit AtomicFile(std::string path);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    void write(const void* data, std::size_t bytes);  // IoError on failure
    void commit();                                    // flush, fsync, rename onto the final path

private:
    std::string path_, tmp_path_;
    std::FILE* file_ = nullptr;
};

}  // namespace brdfz::detail
