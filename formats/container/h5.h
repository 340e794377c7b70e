// A small typed layer over the HDF5 C API for the container: RAII handles, attributes of the few
// kinds the format uses, and datasets that carry their own CRC-32C. Every failure becomes a brdfz
// exception naming the file and the object (IoError when writing, FormatError when reading), with
// HDF5's innermost error message; nothing is printed (HDF5's automatic error report is switched off
// for the calling thread while a Writer or Reader is alive).
//
// Integrity envelope (formats/SPEC.md, "Header"): the file starts with a 4096-byte HDF5 user block
// holding brdfz's own header: magic, the file size, where each dataset's bytes lie, and a CRC-32C of
// every other byte (HDF5's structure: superblock, object headers, attributes). The reader checks it
// before HDF5 parses anything, so HDF5 (whose parser is not hardened against corrupt input) never sees
// a damaged structure, and the datasets' bytes are checked by their own CRC-32C when read.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace brdfz::container::h5 {

enum class DType { U8, I8, U16, U32, U64, F16, F32, F64 };  // F16: IEEE binary16, as h5py/numpy float16
const char* dtype_name(DType t);
std::size_t dtype_size(DType t);

// An HDF5 identifier closed by its matching H5?close on destruction.
class Id {
public:
    using Close = herr_t (*)(hid_t);  // nullptr: a borrowed identifier, not closed
    Id() = default;
    Id(hid_t id, Close close) : id_(id), close_(close) {}
    ~Id() { reset(); }
    Id(Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = H5I_INVALID_HID; }
    Id& operator=(Id&& o) noexcept;
    Id(const Id&) = delete;
    Id& operator=(const Id&) = delete;
    hid_t get() const { return id_; }
    // Closes now; returns false when HDF5 reports a failure (a write that could not be flushed).
    bool reset();

private:
    hid_t id_ = H5I_INVALID_HID;
    Close close_ = nullptr;
};

// Suppresses HDF5's automatic error printing on this thread for its lifetime, restoring the
// previous handler afterwards (the HDF5 build is thread-safe: error stacks are per thread).
class Quiet {
public:
    Quiet();
    ~Quiet();
    Quiet(const Quiet&) = delete;
    Quiet& operator=(const Quiet&) = delete;

private:
    H5E_auto2_t func_ = nullptr;
    void* data_ = nullptr;
};

// Where a dataset's bytes lie in the file.
struct Extent {
    std::uint64_t offset = 0, length = 0;
};

class Writer;
class Reader;

// A group being written.
class WriteNode {
public:
    WriteNode(Writer& writer, Id id, std::string path) : writer_(&writer), id_(std::move(id)), path_(std::move(path)) {}

    WriteNode group(const std::string& name);  // open while the returned node lives
    void attr(const std::string& name, const std::string& value);
    void attr(const std::string& name, std::uint64_t value);
    void attr(const std::string& name, double value);
    void attr(const std::string& name, std::span<const std::string> values);
    void attr(const std::string& name, std::span<const std::uint64_t> values);
    void attr(const std::string& name, std::span<const double> values);
    // A little-endian dataset of `type` in C order, contiguous and unfiltered (so reading is one
    // read of its bytes), with attribute "crc32c" = CRC-32C of those little-endian bytes.
    void dataset(const std::string& name, DType type, const std::vector<std::uint64_t>& shape, const void* data);

    const std::string& path() const { return path_; }
    const std::string& file() const;  // the file being written, as named to the Writer

private:
    void attr_raw(const std::string& name, hid_t file_type, hid_t mem_type, std::span<const std::uint64_t> dims,
                  const void* data);
    [[noreturn]] void fail(const std::string& what) const;

    Writer* writer_;
    Id id_;
    std::string path_;
};

// Builds an HDF5 file for `path` in memory (HDF5's core driver), in the HDF5 1.8 file format, whose
// superblock and object headers also carry HDF5's own checksums, after the brdfz header's room. Only
// close() writes, through formats/detail/atomic_file.h: HDF5 never opens a file by name, so a killed
// write leaves nothing, as for the other formats, and a write error is the AtomicFile's one line.
class Writer {
public:
    explicit Writer(std::string path);
    ~Writer();
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;
    WriteNode root() { return WriteNode(*this, Id(file_.get(), nullptr), ""); }
    // Closes the file, puts the brdfz header in front and writes it to path() atomically; IoError on
    // failure. Nodes must be destroyed first.
    void close();
    const std::string& path() const { return path_; }

    // The core driver's memory, which HDF5 hands to image_free when the file closes (h5.cpp).
    struct Image {
        unsigned char* bytes = nullptr;
        std::size_t capacity = 0;
        bool closed = false;  // HDF5 is done with bytes: they are the finished file, the Writer's to free
    };

private:
    friend class WriteNode;
    Quiet quiet_;
    std::string path_;
    Image image_;  // declared before file_: filled when file_ closes
    Id file_;
    std::vector<Extent> extents_;
};

inline const std::string& WriteNode::file() const { return writer_->path(); }

class Dataset {
public:
    DType type() const { return type_; }
    const std::vector<std::uint64_t>& shape() const { return shape_; }
    std::uint64_t count() const { return count_; }
    std::uint64_t nbytes() const { return count_ * dtype_size(type_); }
    const std::string& path() const { return path_; }
    std::uint32_t stored_crc() const { return crc_; }

    // Reads all elements into `out` (exactly nbytes()) and verifies the CRC-32C; FormatError naming the
    // dataset when they differ. The caller checks shape() and bounds it before allocating `out`.
    void read(void* out) const;

private:
    friend class ReadNode;
    Dataset(const Reader& reader, Id id, std::string path);
    const Reader* reader_;
    Id id_;
    std::string path_;
    DType type_ = DType::U8;
    std::vector<std::uint64_t> shape_;
    std::uint64_t count_ = 1;
    std::uint64_t offset_ = 0;  // of the elements in the file
    std::uint32_t crc_ = 0;
};

// A group being read. Every accessor checks the stored type class, rank and size before reading, and
// throws FormatError naming the file and the attribute or object otherwise.
class ReadNode {
public:
    ReadNode(const Reader& reader, Id id, std::string path) : reader_(&reader), id_(std::move(id)), path_(std::move(path)) {}

    bool has_attr(const std::string& name) const;
    bool has(const std::string& name) const;  // a link (group or dataset)
    std::string str(const std::string& name) const;
    std::uint64_t u64(const std::string& name) const;
    double f64(const std::string& name) const;
    std::vector<std::string> strs(const std::string& name) const;
    std::vector<std::uint64_t> u64s(const std::string& name) const;
    std::vector<double> f64s(const std::string& name) const;
    ReadNode group(const std::string& name) const;
    Dataset dataset(const std::string& name) const;
    std::vector<std::string> datasets() const;  // names of the datasets directly in this group
    std::string child(const std::string& name) const { return path_ + "/" + name; }

    const std::string& file() const;
    const std::string& path() const { return path_; }

private:
    Id open_attr(const std::string& name, H5T_class_t cls, int rank, std::uint64_t* count) const;
    [[noreturn]] void fail(const std::string& what) const;

    const Reader* reader_;
    Id id_;
    std::string path_;
};

class Reader {
public:
    // Checks the brdfz header and the CRC-32C of the file's structure, then opens it with HDF5.
    // FormatError naming the file and what is wrong; IoError when it cannot be read.
    explicit Reader(std::string path);
    ReadNode root() const;
    const std::string& path() const { return path_; }
    std::uint64_t file_size() const { return size_; }
    // Whether the header lists exactly this byte range as a dataset's.
    bool has_extent(const Extent& e) const;
    // Reads a byte range into `out`; returns its CRC-32C. IoError when the file cannot be read.
    std::uint32_t read_extent(const Extent& e, void* out) const;

private:
    Quiet quiet_;
    std::string path_;
    std::uint64_t size_ = 0;
    std::vector<Extent> extents_;
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> raw_{nullptr, &std::fclose};  // the verified file
    Id file_;
};

// Bounds on what a reader accepts before allocating: strings and list attributes.
inline constexpr std::uint64_t kMaxString = 1 << 20;
inline constexpr std::uint64_t kMaxList = 1 << 16;

// The brdfz header in the HDF5 user block (formats/SPEC.md).
inline constexpr std::uint64_t kHeaderSize = 4096;
inline constexpr std::uint32_t kHeaderVersion = 1;
inline constexpr std::uint32_t kMaxExtents = (kHeaderSize - 36) / 16;

}  // namespace brdfz::container::h5
