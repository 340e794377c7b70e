// Atomic output files, for every writer. The bytes go to an unnamed file in the output's folder
// (O_TMPFILE), which becomes NAME only in commit(): a failed, thrown-through or killed write (SIGKILL
// included) leaves neither NAME nor a temporary. Where the file system has no O_TMPFILE (or /proc is
// not mounted), a named NAME.tmp-XXXXXX beside NAME is written instead, locked (flock) while it is
// open; a killed write leaves it behind, and the next write of NAME removes every unlocked one.
// Writers that stream bytes call write() (the container writes the image HDF5 built in memory); a
// library that opens the output by name (OpenEXR) writes to open_path(), a name of the same file, and
// must have closed it before commit().
// Modes: a new file gets 0666 less the umask, as open(2) gives; a replaced one keeps its mode.
// Only regular files are replaced: a NAME that is a device, a FIFO, a socket or a folder is refused
// (IoError, as brdfz::check_output says) before anything is written and again at commit(); a symbolic
// link to a regular file is written through (the link stays, its target gets the bytes), one to nothing
// or to anything else is refused.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>

namespace brdfz::detail {

class AtomicFile {
public:
    // Named: always the NAME.tmp-XXXXXX fallback (what a file system without O_TMPFILE gets).
    enum class Temporary { Unnamed, Named };

    // IoError naming `path` when the temporary cannot be created (missing folder, permissions).
    explicit AtomicFile(std::string path, Temporary kind = Temporary::Unnamed);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::string& path() const { return path_; }
    // Where the bytes go: path(), or the regular file a symbolic link at path() leads to.
    const std::string& target() const { return target_; }
    // Where a library that opens files by name writes the bytes: /proc/self/fd/N of the unnamed file,
    // or the temporary's name (HDF5 cannot take the first: it resolves the link's target by name).
    const std::string& open_path() const { return open_path_; }
    bool unnamed() const { return tmp_path_.empty(); }

    void write(const void* data, std::size_t bytes);  // IoError on failure
    // Flushes and fsyncs the bytes, gives them the mode (a replaced file's, or the umask's) and puts
    // them at path() in one step (link or rename); IoError otherwise, and then nothing is at path()
    // that was not there before.
    void commit();

private:
    void open_named();

    std::string path_, target_, dir_, open_path_, tmp_path_;
    int fd_ = -1;
    std::FILE* stream_ = nullptr;  // write()'s buffer over fd_, opened on first use
    bool committed_ = false;
};

// Removes the NAME.tmp-XXXXXX files that killed writes of `path` left beside it: those of this user
// that no live writer holds locked. Called by every AtomicFile; returns how many it removed.
int remove_stale_temporaries(const std::string& path);

}  // namespace brdfz::detail
