#include "h5.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>

#include "brdfz/errors.h"
#include "checksum.h"
#include "detail/atomic_file.h"

namespace brdfz::container::h5 {
namespace {

// HDF5's innermost (most specific) error message on this thread's stack, e.g. "incorrect metadata
// checksum after all read attempts"; empty when the stack is empty.
std::string hdf5_message() {
    std::string msg;
    H5Ewalk2(
        H5E_DEFAULT, H5E_WALK_UPWARD,
        [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
            if (n == 0 && e->desc) *static_cast<std::string*>(data) = e->desc;
            return 0;
        },
        &msg);
    H5Eclear2(H5E_DEFAULT);
    return msg.empty() ? std::string() : " (HDF5: " + msg + ")";
}

// HDF5 (before 1.14.4) has no predefined half type: derive it from float32 the way h5py does, so that
// h5py and numpy read it as float16. Locked: shared for the process, closed when the library shuts down.
hid_t half_type() {
    static const hid_t t = [] {
        const hid_t h = H5Tcopy(H5T_IEEE_F32LE);
        H5Tset_fields(h, 15, 10, 5, 0, 10);
        H5Tset_size(h, 2);
        H5Tset_ebias(h, 15);
        H5Tlock(h);
        return h;
    }();
    return t;
}

hid_t file_type(DType t) {
    switch (t) {
        case DType::U8: return H5T_STD_U8LE;
        case DType::I8: return H5T_STD_I8LE;
        case DType::U16: return H5T_STD_U16LE;
        case DType::F16: return half_type();
        case DType::U32: return H5T_STD_U32LE;
        case DType::U64: return H5T_STD_U64LE;
        case DType::F32: return H5T_IEEE_F32LE;
        case DType::F64: return H5T_IEEE_F64LE;
    }
    return H5I_INVALID_HID;  // unreachable: every enumerator is handled
}

Id string_type(std::size_t size) {
    Id t(H5Tcopy(H5T_C_S1), &H5Tclose);
    H5Tset_size(t.get(), size == 0 ? 1 : size);
    H5Tset_strpad(t.get(), H5T_STR_NULLPAD);
    return t;
}

std::string display(const std::string& path) { return path.empty() ? "/" : path; }

constexpr unsigned char kMagic[8] = {0x89, 'B', 'R', 'D', 'F', 'Z', '\r', '\n'};

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

void put32(unsigned char* p, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = static_cast<unsigned char>(v >> (8 * k));
}
void put64(unsigned char* p, std::uint64_t v) {
    for (int k = 0; k < 8; ++k) p[k] = static_cast<unsigned char>(v >> (8 * k));
}
std::uint32_t get32(const unsigned char* p) {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= std::uint32_t{p[k]} << (8 * k);
    return v;
}
std::uint64_t get64(const unsigned char* p) {
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= std::uint64_t{p[k]} << (8 * k);
    return v;
}

// CRC-32C of every byte from the end of the header to `size` that no extent covers (the extents are
// sorted and disjoint); read(pos, n, out) fetches n bytes at pos. False when a read fails.
template <typename Read>
bool structure_crc(std::uint64_t size, const std::vector<Extent>& extents, Read read, std::uint32_t* crc) {
    std::vector<unsigned char> chunk(1 << 16);
    std::uint32_t c = 0;
    std::uint64_t pos = kHeaderSize;
    const auto gap = [&](std::uint64_t end) {
        while (pos < end) {
            const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), end - pos));
            if (!read(pos, n, chunk.data())) return false;
            c = crc32c(chunk.data(), n, c);
            pos += n;
        }
        return true;
    };
    for (const Extent& e : extents) {
        if (!gap(e.offset)) return false;
        pos = e.offset + e.length;
    }
    if (!gap(size)) return false;
    *crc = c;
    return true;
}

// Creation properties shared by the root group and every group and dataset: attributes and links
// are kept in the object header (compact storage), which HDF5's checksum covers; the dense storage
// it switches to by default beyond 8 of them (a fractal heap) is not checksummed. No object times:
// the same content gives the same bytes.
void keep_compact(hid_t plist, bool links) {
    H5Pset_attr_phase_change(plist, 1024, 0);
    if (links) H5Pset_link_phase_change(plist, 1024, 0);
    H5Pset_obj_track_times(plist, false);
}

}  // namespace

const char* dtype_name(DType t) {
    switch (t) {
        case DType::U8: return "uint8";
        case DType::I8: return "int8";
        case DType::U16: return "uint16";
        case DType::U32: return "uint32";
        case DType::U64: return "uint64";
        case DType::F16: return "float16";
        case DType::F32: return "float32";
        case DType::F64: return "float64";
    }
    return "?";
}

std::size_t dtype_size(DType t) {
    switch (t) {
        case DType::U8: case DType::I8: return 1;
        case DType::U16: case DType::F16: return 2;
        case DType::U32: case DType::F32: return 4;
        case DType::U64: case DType::F64: return 8;
    }
    return 0;
}

Id& Id::operator=(Id&& o) noexcept {
    if (this != &o) {
        reset();
        id_ = o.id_;
        close_ = o.close_;
        o.id_ = H5I_INVALID_HID;
    }
    return *this;
}

bool Id::reset() {
    bool ok = true;
    if (id_ >= 0 && close_) ok = close_(id_) >= 0;
    id_ = H5I_INVALID_HID;
    return ok;
}

Quiet::Quiet() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}
Quiet::~Quiet() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }

// ---- writing ----

void WriteNode::fail(const std::string& what) const {
    throw IoError(writer_->path(), "cannot write " + display(path_) + ": " + what + hdf5_message());
}

WriteNode WriteNode::group(const std::string& name) {
    Id gcpl(H5Pcreate(H5P_GROUP_CREATE), &H5Pclose);
    keep_compact(gcpl.get(), true);
    Id g(H5Gcreate2(id_.get(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), &H5Gclose);
    if (g.get() < 0) fail("cannot create group '" + name + "'");
    return WriteNode(*writer_, std::move(g), path_ + "/" + name);
}

void WriteNode::attr_raw(const std::string& name, hid_t ftype, hid_t mtype, std::span<const std::uint64_t> dims,
                         const void* data) {
    std::vector<hsize_t> d(dims.begin(), dims.end());
    Id space(dims.empty() ? H5Screate(H5S_SCALAR) : H5Screate_simple(static_cast<int>(d.size()), d.data(), nullptr),
             &H5Sclose);
    Id a(H5Acreate2(id_.get(), name.c_str(), ftype, space.get(), H5P_DEFAULT, H5P_DEFAULT), &H5Aclose);
    if (a.get() < 0 || H5Awrite(a.get(), mtype, data) < 0) fail("attribute '" + name + "'");
}

void WriteNode::attr(const std::string& name, const std::string& value) {
    const Id t = string_type(value.size());
    attr_raw(name, t.get(), t.get(), {}, value.empty() ? "" : value.data());
}

void WriteNode::attr(const std::string& name, std::uint64_t value) {
    attr_raw(name, H5T_STD_U64LE, H5T_NATIVE_UINT64, {}, &value);
}

void WriteNode::attr(const std::string& name, double value) {
    attr_raw(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &value);
}

void WriteNode::attr(const std::string& name, std::span<const std::string> values) {
    std::size_t width = 1;
    for (const std::string& v : values) width = std::max(width, v.size());
    std::vector<char> packed(values.size() * width, '\0');
    for (std::size_t k = 0; k < values.size(); ++k) std::memcpy(packed.data() + k * width, values[k].data(), values[k].size());
    const Id t = string_type(width);
    const std::uint64_t n = values.size();
    attr_raw(name, t.get(), t.get(), std::span(&n, 1), packed.data());
}

void WriteNode::attr(const std::string& name, std::span<const std::uint64_t> values) {
    const std::uint64_t n = values.size();
    attr_raw(name, H5T_STD_U64LE, H5T_NATIVE_UINT64, std::span(&n, 1), values.data());
}

void WriteNode::attr(const std::string& name, std::span<const double> values) {
    const std::uint64_t n = values.size();
    attr_raw(name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, std::span(&n, 1), values.data());
}

void WriteNode::dataset(const std::string& name, DType type, const std::vector<std::uint64_t>& shape,
                        const void* data) {
    static_assert(std::endian::native == std::endian::little, "the container writer assumes a little-endian host");
    std::uint64_t count = 1;
    for (std::uint64_t d : shape) count *= d;
    std::vector<hsize_t> dims(shape.begin(), shape.end());
    Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), &H5Sclose);
    Id dcpl(H5Pcreate(H5P_DATASET_CREATE), &H5Pclose);
    keep_compact(dcpl.get(), false);
    Id d(H5Dcreate2(id_.get(), name.c_str(), file_type(type), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
         &H5Dclose);
    // The file type is the little-endian memory type on this host, so HDF5 copies bytes unconverted.
    if (d.get() < 0 || H5Dwrite(d.get(), file_type(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
        fail("dataset '" + name + "'");
    const haddr_t offset = H5Dget_offset(d.get());
    if (offset == HADDR_UNDEF || H5Dget_storage_size(d.get()) != count * dtype_size(type))
        fail("dataset '" + name + "' was not stored contiguously");
    writer_->extents_.push_back({offset, count * dtype_size(type)});
    WriteNode node(*writer_, std::move(d), path_ + "/" + name);
    node.attr("crc32c", std::uint64_t{crc32c(data, count * dtype_size(type))});
}

namespace {

// The core driver's memory comes from these callbacks, so that the file it holds when it closes (the
// superblock and metadata as H5Fclose finished them) is kept rather than freed. H5Fget_file_image is
// no substitute: in HDF5 1.10 its copy of a file with a user block has a wrong superblock checksum.
// Only the buffer the file grew into is kept; anything else HDF5 allocates through them is freed.
H5FD_file_image_callbacks_t image_callbacks(Writer::Image* image) {
    H5FD_file_image_callbacks_t c{};
    c.image_malloc = [](std::size_t size, H5FD_file_image_op_t, void*) -> void* { return std::malloc(size); };
    c.image_memcpy = [](void* dest, const void* src, std::size_t size, H5FD_file_image_op_t, void*) -> void* {
        return std::memcpy(dest, src, size);
    };
    c.image_realloc = [](void* ptr, std::size_t size, H5FD_file_image_op_t, void* udata) -> void* {
        auto* im = static_cast<Writer::Image*>(udata);
        void* grown = std::realloc(ptr, size);
        if (grown && (ptr == im->bytes || !im->bytes)) {
            im->bytes = static_cast<unsigned char*>(grown);
            im->capacity = size;
        }
        return grown;
    };
    c.image_free = [](void* ptr, H5FD_file_image_op_t op, void* udata) -> herr_t {
        auto* im = static_cast<Writer::Image*>(udata);
        if (ptr && ptr == im->bytes && op == H5FD_FILE_IMAGE_OP_FILE_CLOSE) {
            im->closed = true;
            return 0;
        }
        if (ptr == im->bytes) im->bytes = nullptr;
        std::free(ptr);
        return 0;
    };
    c.udata_copy = [](void* udata) -> void* { return udata; };
    c.udata_free = [](void*) -> herr_t { return 0; };
    c.udata = image;
    return c;
}

}  // namespace

Writer::Writer(std::string path) : path_(std::move(path)) {
    Id fcpl(H5Pcreate(H5P_FILE_CREATE), &H5Pclose);
    keep_compact(fcpl.get(), true);
    H5Pset_userblock(fcpl.get(), kHeaderSize);
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), &H5Pclose);
    H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18);
    H5Pset_fapl_core(fapl.get(), 1 << 20, false);  // in memory, nothing backed by a file
    H5FD_file_image_callbacks_t callbacks = image_callbacks(&image_);
    H5Pset_file_image_callbacks(fapl.get(), &callbacks);
    // HDF5 first opens an existing file of the name it is given (it reads it whole with this driver,
    // and would block on a FIFO): the name is one no file system has, unique to this writer.
    const std::string name = "/proc/self/fd/-1/brdfz-writer-" + std::to_string(reinterpret_cast<std::uintptr_t>(this));
    file_ = Id(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()), &H5Fclose);
    if (file_.get() < 0) throw IoError(path_, "cannot create HDF5 file" + hdf5_message());
}

Writer::~Writer() {
    file_.reset();
    if (image_.closed) std::free(image_.bytes);
}

void Writer::close() {
    if (extents_.size() > kMaxExtents) throw IoError(path_, "too many datasets for the header");
    // The file's extent, from the superblock (where the user block ends) to its end, once flushed.
    const ssize_t size =
        H5Fflush(file_.get(), H5F_SCOPE_GLOBAL) < 0 ? -1 : H5Fget_file_image(file_.get(), nullptr, 0);
    if (size <= 0 || !file_.reset() || !image_.closed || kHeaderSize + static_cast<std::size_t>(size) > image_.capacity)
        throw IoError(path_, "cannot complete HDF5 write" + hdf5_message());
    const std::span<unsigned char> image(image_.bytes, kHeaderSize + static_cast<std::size_t>(size));
    std::sort(extents_.begin(), extents_.end(), [](const Extent& a, const Extent& b) { return a.offset < b.offset; });

    std::uint32_t crc = 0;
    const auto from_image = [&](std::uint64_t pos, std::size_t n, unsigned char* out) {
        if (pos > image.size() || n > image.size() - pos) return false;
        std::memcpy(out, image.data() + pos, n);
        return true;
    };
    if (!structure_crc(image.size(), extents_, from_image, &crc)) throw IoError(path_, "dataset extents outside the file");
    unsigned char* header = image.data();
    std::memset(header, 0, kHeaderSize);
    std::memcpy(header, kMagic, sizeof kMagic);
    put32(header + 8, kHeaderVersion);
    put32(header + 12, static_cast<std::uint32_t>(extents_.size()));
    put64(header + 16, image.size());
    put32(header + 24, crc);
    unsigned char* p = header + 32;
    for (const Extent& e : extents_) {
        put64(p, e.offset);
        put64(p + 8, e.length);
        p += 16;
    }
    put32(header + kHeaderSize - 4, crc32c(header, kHeaderSize - 4));
    brdfz::detail::AtomicFile out(path_);
    out.write(image.data(), image.size());
    out.commit();
}

// ---- reading ----

Reader::Reader(std::string path) : path_(std::move(path)) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path_, ec);
    if (ec) throw IoError(path_, "cannot read: " + ec.message());
    if (size > static_cast<std::uintmax_t>(std::numeric_limits<long>::max())) throw UnsupportedError(path_, "file too large");
    size_ = size;
    File f(std::fopen(path_.c_str(), "rb"), &std::fclose);
    if (!f) throw IoError(path_, std::string("cannot open: ") + std::strerror(errno));

    unsigned char header[kHeaderSize] = {};
    const std::size_t got = std::fread(header, 1, sizeof header, f.get());
    if (got < sizeof kMagic || std::memcmp(header, kMagic, sizeof kMagic) != 0)
        throw FormatError(path_, "not a .brdfz container (no brdfz header at the start of the file)");
    if (got < sizeof header)
        throw FormatError(path_, "truncated: " + std::to_string(size_) + " bytes, shorter than the " +
                                     std::to_string(kHeaderSize) + "-byte header");
    // Every header version ends in the CRC-32C of the bytes before it, so it is checked first.
    if (get32(header + kHeaderSize - 4) != crc32c(header, kHeaderSize - 4))
        throw FormatError(path_, "corrupt header (its CRC-32C does not match)");
    const std::uint32_t version = get32(header + 8), n = get32(header + 12);
    if (version != kHeaderVersion)
        throw UnsupportedError(path_, "header version " + std::to_string(version) + " (this brdfz reads version " +
                                          std::to_string(kHeaderVersion) + ")");
    if (n > kMaxExtents) throw FormatError(path_, "corrupt header: " + std::to_string(n) + " dataset extents");
    const std::uint64_t recorded = get64(header + 16);
    if (recorded != size_)
        throw FormatError(path_, std::string(size_ < recorded ? "truncated" : "oversized") + ": " + std::to_string(size_) +
                                     " bytes, the header records " + std::to_string(recorded));
    std::uint64_t previous_end = kHeaderSize;
    for (std::uint32_t k = 0; k < n; ++k) {
        const Extent e{get64(header + 32 + 16 * k), get64(header + 40 + 16 * k)};
        if (e.offset < previous_end || e.length == 0 || e.offset > size_ || e.length > size_ - e.offset)
            throw FormatError(path_, "corrupt header: dataset extent " + std::to_string(k) + " is out of order or "
                                     "outside the file");
        previous_end = e.offset + e.length;
        extents_.push_back(e);
    }
    std::uint32_t crc = 0;
    const auto from_file = [&](std::uint64_t pos, std::size_t n, unsigned char* out) {
        return std::fseek(f.get(), static_cast<long>(pos), SEEK_SET) == 0 && std::fread(out, 1, n, f.get()) == n;
    };
    if (!structure_crc(size_, extents_, from_file, &crc)) throw IoError(path_, "read failed (file changed while reading?)");
    if (crc != get32(header + 24))
        throw FormatError(path_, "corrupt: the HDF5 structure (metadata and attributes, outside the datasets) does "
                                 "not match its CRC-32C");
    raw_ = std::move(f);

    Id fapl(H5Pcreate(H5P_FILE_ACCESS), &H5Pclose);
    // Reading needs no lock, and some file systems refuse one.
    H5Pset_file_locking(fapl.get(), false, true);
    file_ = Id(H5Fopen(path_.c_str(), H5F_ACC_RDONLY, fapl.get()), &H5Fclose);
    if (file_.get() < 0) throw FormatError(path_, "unreadable HDF5 structure" + hdf5_message());
}

std::uint32_t Reader::read_extent(const Extent& e, void* out) const {
    // In slices, each checksummed right after it lands, while it is still in cache: one pass over the
    // memory, on the caller's thread.
    constexpr std::uint64_t kSlice = 1 << 18;  // 256 KiB: well inside a 1 MiB L2
    auto* p = static_cast<unsigned char*>(out);
    std::uint32_t crc = 0;
    for (std::uint64_t done = 0; done < e.length;) {
        const std::size_t n = static_cast<std::size_t>(std::min(kSlice, e.length - done));
        const ssize_t got = ::pread(::fileno(raw_.get()), p + done, n, static_cast<off_t>(e.offset + done));
        if (got <= 0) throw IoError(path_, "read failed (file changed while reading?)");
        crc = crc32c(p + done, static_cast<std::size_t>(got), crc);
        done += static_cast<std::uint64_t>(got);
    }
    return crc;
}

bool Reader::has_extent(const Extent& e) const {
    return std::any_of(extents_.begin(), extents_.end(),
                       [&](const Extent& x) { return x.offset == e.offset && x.length == e.length; });
}

ReadNode Reader::root() const { return ReadNode(*this, Id(file_.get(), nullptr), ""); }

const std::string& ReadNode::file() const { return reader_->path(); }

void ReadNode::fail(const std::string& what) const {
    throw FormatError(file(), display(path_) + ": " + what + hdf5_message());
}

bool ReadNode::has_attr(const std::string& name) const {
    const htri_t r = H5Aexists(id_.get(), name.c_str());
    if (r < 0) fail("cannot list attribute '" + name + "'");
    return r > 0;
}

bool ReadNode::has(const std::string& name) const {
    const htri_t r = H5Lexists(id_.get(), name.c_str(), H5P_DEFAULT);
    if (r < 0) fail("cannot look up '" + name + "'");
    return r > 0;
}

Id ReadNode::open_attr(const std::string& name, H5T_class_t cls, int rank, std::uint64_t* count) const {
    if (!has_attr(name)) fail("missing attribute '" + name + "'");
    Id a(H5Aopen(id_.get(), name.c_str(), H5P_DEFAULT), &H5Aclose);
    if (a.get() < 0) fail("cannot open attribute '" + name + "'");
    Id t(H5Aget_type(a.get()), &H5Tclose);
    Id s(H5Aget_space(a.get()), &H5Sclose);
    if (t.get() < 0 || s.get() < 0) fail("cannot read attribute '" + name + "'");
    static const char* const kClass[] = {"integer", "float", "time", "string", "bitfield", "opaque",
                                         "compound", "reference", "enum", "variable-length", "array"};
    const H5T_class_t got = H5Tget_class(t.get());
    if (got != cls) {
        const std::string got_name = got >= 0 && got < 11 ? kClass[got] : "unknown";
        fail("attribute '" + name + "' is of type " + got_name + ", expected " + kClass[cls]);
    }
    if (cls == H5T_STRING && H5Tis_variable_str(t.get()) != 0)
        fail("attribute '" + name + "' is a variable-length string (the container stores fixed-length ones)");
    const int r = H5Sget_simple_extent_ndims(s.get());
    hsize_t n = 1;
    if (r != rank || (r == 1 && H5Sget_simple_extent_dims(s.get(), &n, nullptr) != 1))
        fail("attribute '" + name + "' has rank " + std::to_string(r) + ", expected " + std::to_string(rank));
    if (n > kMaxList) fail("attribute '" + name + "' holds " + std::to_string(n) + " entries, more than the container allows");
    *count = n;
    return a;
}

std::string ReadNode::str(const std::string& name) const {
    std::uint64_t n = 0;
    Id a = open_attr(name, H5T_STRING, 0, &n);
    Id t(H5Aget_type(a.get()), &H5Tclose);
    const std::size_t size = H5Tget_size(t.get());
    if (size == 0 || size > kMaxString) fail("attribute '" + name + "' has an invalid string size");
    std::string s(size, '\0');
    const Id mt = string_type(size);
    if (H5Aread(a.get(), mt.get(), s.data()) < 0) fail("cannot read attribute '" + name + "'");
    s.resize(std::strlen(s.c_str()));
    return s;
}

std::vector<std::string> ReadNode::strs(const std::string& name) const {
    std::uint64_t n = 0;
    Id a = open_attr(name, H5T_STRING, 1, &n);
    Id t(H5Aget_type(a.get()), &H5Tclose);
    const std::size_t width = H5Tget_size(t.get());
    if (width == 0 || width > kMaxString || n * width > kMaxString)
        fail("attribute '" + name + "' has an invalid string size");
    std::vector<char> packed(n * width + 1, '\0');
    const Id mt = string_type(width);
    if (H5Aread(a.get(), mt.get(), packed.data()) < 0) fail("cannot read attribute '" + name + "'");
    std::vector<std::string> out;
    for (std::uint64_t k = 0; k < n; ++k) {
        const char* p = packed.data() + k * width;
        out.emplace_back(p, strnlen(p, width));
    }
    return out;
}

std::uint64_t ReadNode::u64(const std::string& name) const {
    std::uint64_t n = 0, v = 0;
    Id a = open_attr(name, H5T_INTEGER, 0, &n);
    if (H5Aread(a.get(), H5T_NATIVE_UINT64, &v) < 0) fail("cannot read attribute '" + name + "'");
    return v;
}

double ReadNode::f64(const std::string& name) const {
    std::uint64_t n = 0;
    double v = 0;
    Id a = open_attr(name, H5T_FLOAT, 0, &n);
    if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0) fail("cannot read attribute '" + name + "'");
    return v;
}

std::vector<std::uint64_t> ReadNode::u64s(const std::string& name) const {
    std::uint64_t n = 0;
    Id a = open_attr(name, H5T_INTEGER, 1, &n);
    std::vector<std::uint64_t> v(n);
    if (n && H5Aread(a.get(), H5T_NATIVE_UINT64, v.data()) < 0) fail("cannot read attribute '" + name + "'");
    return v;
}

std::vector<double> ReadNode::f64s(const std::string& name) const {
    std::uint64_t n = 0;
    Id a = open_attr(name, H5T_FLOAT, 1, &n);
    std::vector<double> v(n);
    if (n && H5Aread(a.get(), H5T_NATIVE_DOUBLE, v.data()) < 0) fail("cannot read attribute '" + name + "'");
    return v;
}

ReadNode ReadNode::group(const std::string& name) const {
    if (!has(name)) fail("missing group '" + name + "'");
    Id g(H5Gopen2(id_.get(), name.c_str(), H5P_DEFAULT), &H5Gclose);
    if (g.get() < 0) fail("cannot open group '" + name + "'");
    return ReadNode(*reader_, std::move(g), child(name));
}

Dataset ReadNode::dataset(const std::string& name) const {
    if (!has(name)) fail("missing dataset '" + name + "'");
    Id d(H5Dopen2(id_.get(), name.c_str(), H5P_DEFAULT), &H5Dclose);
    if (d.get() < 0) fail("cannot open dataset '" + name + "'");
    return Dataset(*reader_, std::move(d), child(name));
}

std::vector<std::string> ReadNode::datasets() const {
    std::vector<std::string> names;
    const auto visit = [](hid_t group, const char* name, const H5L_info_t*, void* data) -> herr_t {
        auto* out = static_cast<std::vector<std::string>*>(data);
        if (out->size() >= kMaxList) return -1;
        Id o(H5Oopen(group, name, H5P_DEFAULT), &H5Oclose);
        if (o.get() >= 0 && H5Iget_type(o.get()) == H5I_DATASET) out->emplace_back(name);
        return 0;
    };
    if (H5Literate(id_.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, visit, &names) < 0) fail("cannot list the group");
    return names;
}

Dataset::Dataset(const Reader& reader, Id id, std::string path)
    : reader_(&reader), id_(std::move(id)), path_(std::move(path)) {
    const auto fail = [&](const std::string& what) { throw FormatError(reader_->path(), path_ + ": " + what + hdf5_message()); };
    Id t(H5Dget_type(id_.get()), &H5Tclose);
    Id s(H5Dget_space(id_.get()), &H5Sclose);
    if (t.get() < 0 || s.get() < 0) fail("cannot read the dataset's type and shape");
    bool known = false;
    for (DType c : {DType::U8, DType::I8, DType::U16, DType::U32, DType::U64, DType::F16, DType::F32, DType::F64}) {
        if (H5Tequal(t.get(), file_type(c)) > 0) {
            type_ = c;
            known = true;
        }
    }
    if (!known) fail("unsupported element type (expected little-endian uint8/16/32/64, int8 or float16/32/64)");
    const int rank = H5Sget_simple_extent_ndims(s.get());
    if (rank < 1 || rank > 8) fail("unsupported rank " + std::to_string(rank));
    std::vector<hsize_t> dims(rank);
    H5Sget_simple_extent_dims(s.get(), dims.data(), nullptr);
    // Bounded by the file size at every step, so the product cannot overflow, and no dataset can
    // claim more memory than its file could hold.
    const std::uint64_t limit = reader_->file_size() / dtype_size(type_);
    for (hsize_t d : dims) {
        if (d == 0 || count_ > limit / d) fail("declared shape exceeds the file's size");
        count_ *= d;
        shape_.push_back(d);
    }
    const std::uint64_t crc = ReadNode(*reader_, Id(id_.get(), nullptr), path_).u64("crc32c");
    if (crc > 0xFFFFFFFFu) fail("attribute 'crc32c' out of range");
    crc_ = static_cast<std::uint32_t>(crc);
    // Every byte is covered by a checksum: the structure's, or its dataset's when the header lists it.
    offset_ = H5Dget_offset(id_.get());
    if (offset_ == HADDR_UNDEF || !reader_->has_extent({offset_, nbytes()}))
        fail("data is not where the header records a dataset");
}

void Dataset::read(void* out) const {
    // The data are contiguous, unfiltered and little-endian (checked on opening), so their bytes in the
    // file are the elements: read them directly, checksumming as they arrive, rather than via H5Dread.
    const std::uint32_t crc = reader_->read_extent({offset_, nbytes()}, out);
    if (crc != crc_) {
        char buf[96];
        std::snprintf(buf, sizeof buf, " (CRC-32C 0x%08x, stored 0x%08x)", crc, crc_);
        throw FormatError(reader_->path(), "dataset " + path_ + " is corrupt" + buf);
    }
}

}  // namespace brdfz::container::h5
