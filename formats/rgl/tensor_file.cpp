#include "tensor_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>

#include "brdfz/errors.h"
#include "detail/bytes.h"

namespace brdfz::rgl::detail {
namespace {

constexpr char kMagic[12] = {'t', 'e', 'n', 's', 'o', 'r', '_', 'f', 'i', 'l', 'e', '\0'};
constexpr std::uint8_t kVersion[2] = {1, 0};

std::uint64_t element_size(DType t) {
    switch (t) {
        case DType::U8: case DType::I8: return 1;
        case DType::U16: case DType::I16: case DType::F16: return 2;
        case DType::U32: case DType::I32: case DType::F32: return 4;
        case DType::U64: case DType::I64: case DType::F64: return 8;
    }
    return 0;  // unreachable: dtype codes are range-checked when parsed
}

// Sequential reads through the field table. Every read is checked against the file size first, so
// a short file is reported as a truncated header rather than as an I/O error.
class HeaderReader {
public:
    HeaderReader(const std::string& path, std::FILE* f, std::uint64_t size) : path_(path), f_(f), size_(size) {}

    void bytes(void* out, std::uint64_t n, const char* what) {
        if (size_ - pos_ < n)
            throw FormatError(path_, std::string("truncated header: file ends inside ") + what + " at byte " +
                                         std::to_string(pos_));
        if (std::fread(out, 1, n, f_) != n) throw IoError(path_, "read failed (file changed while reading?)");
        pos_ += n;
    }
    template <typename T>
    T number(const char* what) {
        T v;
        bytes(&v, sizeof v, what);
        return brdfz::detail::from_little_endian(v);
    }

private:
    const std::string& path_;
    std::FILE* f_;
    std::uint64_t size_, pos_ = 0;
};

}  // namespace

const char* dtype_name(DType t) {
    static constexpr const char* kNames[] = {"uint8", "int8",  "uint16",  "int16",   "uint32", "int32",
                                             "uint64", "int64", "float16", "float32", "float64"};
    return kNames[static_cast<int>(t) - 1];
}

TensorFile::TensorFile(std::string path) : path_(std::move(path)), file_(nullptr, &std::fclose) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path_, ec);
    if (ec) throw IoError(path_, "cannot read: " + ec.message());
    // fseek takes a long; any real file fits, and a larger one cannot be addressed anyway.
    if (size > static_cast<std::uintmax_t>(std::numeric_limits<long>::max()))
        throw UnsupportedError(path_, "file too large");
    size_ = size;
    file_.reset(std::fopen(path_.c_str(), "rb"));
    if (!file_) throw IoError(path_, std::string("cannot open: ") + std::strerror(errno));

    HeaderReader in(path_, file_.get(), size_);
    char magic[sizeof kMagic];
    in.bytes(magic, sizeof magic, "the magic bytes");
    if (std::memcmp(magic, kMagic, sizeof kMagic) != 0)
        throw FormatError(path_, "not a tensor_file (the file does not start with \"tensor_file\\0\")");
    std::uint8_t version[2];
    in.bytes(version, sizeof version, "the version");
    if (version[0] != kVersion[0] || version[1] != kVersion[1])
        throw FormatError(path_, "unknown tensor_file version " + std::to_string(version[0]) + "." +
                                     std::to_string(version[1]) + " (expected 1.0)");

    const auto n_fields = in.number<std::uint32_t>("the field count");
    if (n_fields > kMaxFields)
        throw FormatError(path_, "field count " + std::to_string(n_fields) + " exceeds " + std::to_string(kMaxFields));

    fields_.reserve(n_fields);
    for (std::uint32_t k = 0; k < n_fields; ++k) {
        Field f;
        const auto name_length = in.number<std::uint16_t>("a field name length");
        if (name_length == 0 || name_length > kMaxNameLength)
            throw FormatError(path_, "field " + std::to_string(k) + ": name length " + std::to_string(name_length) +
                                         " outside 1.." + std::to_string(kMaxNameLength));
        f.name.resize(name_length);
        in.bytes(f.name.data(), name_length, "a field name");
        const std::string where = "field '" + f.name + "': ";
        if (find(f.name)) throw FormatError(path_, where + "appears twice");

        const auto rank = in.number<std::uint16_t>("a field rank");
        if (rank > kMaxRank)
            throw FormatError(path_, where + "rank " + std::to_string(rank) + " exceeds " + std::to_string(kMaxRank));
        const auto dtype = in.number<std::uint8_t>("a field dtype");
        if (dtype < static_cast<std::uint8_t>(DType::U8) || dtype > static_cast<std::uint8_t>(DType::F64))
            throw FormatError(path_, where + "unknown dtype code " + std::to_string(dtype));
        f.dtype = static_cast<DType>(dtype);
        f.offset = in.number<std::uint64_t>("a field offset");

        // The product is bounded by what the file can hold at each step, so it cannot overflow.
        const std::uint64_t elem = element_size(f.dtype);
        const std::uint64_t max_count = f.offset <= size_ ? (size_ - f.offset) / elem : 0;
        f.shape.resize(rank);
        for (auto& d : f.shape) d = in.number<std::uint64_t>("a field shape");
        for (std::uint64_t d : f.shape) {
            if (d != 0 && f.count > max_count / d)
                throw FormatError(path_, where + "data (offset " + std::to_string(f.offset) + ", " +
                                             std::to_string(rank) + "-d " + dtype_name(f.dtype) +
                                             ") extends past the end of the file (" + std::to_string(size_) +
                                             " bytes)");
            f.count *= d;
        }
        if (f.offset > size_ || f.count > max_count)
            throw FormatError(path_, where + "data at offset " + std::to_string(f.offset) + " (" +
                                         std::to_string(f.count * elem) + " bytes) extends past the end of the file (" +
                                         std::to_string(size_) + " bytes)");
        fields_.push_back(std::move(f));
    }
}

const Field* TensorFile::find(std::string_view name) const {
    for (const Field& f : fields_)
        if (f.name == name) return &f;
    return nullptr;
}

void TensorFile::read_at(std::uint64_t offset, void* out, std::uint64_t bytes) const {
    if (bytes == 0) return;
    if (std::fseek(file_.get(), static_cast<long>(offset), SEEK_SET) != 0 ||
        std::fread(out, 1, bytes, file_.get()) != bytes)
        throw IoError(path_, "read failed (file changed while reading?)");
}

std::vector<float> TensorFile::read_f32(const Field& f) const {
    if (f.dtype != DType::F32)
        throw FormatError(path_, "field '" + f.name + "' is " + dtype_name(f.dtype) + ", expected float32");
    std::vector<float> v(f.count);
    read_at(f.offset, v.data(), f.count * sizeof(float));
    for (float& x : v) x = brdfz::detail::from_little_endian(x);
    return v;
}

std::vector<std::uint8_t> TensorFile::read_u8(const Field& f) const {
    if (f.dtype != DType::U8)
        throw FormatError(path_, "field '" + f.name + "' is " + dtype_name(f.dtype) + ", expected uint8");
    std::vector<std::uint8_t> v(f.count);
    read_at(f.offset, v.data(), f.count);
    return v;
}

}  // namespace brdfz::rgl::detail
