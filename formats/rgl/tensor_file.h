// The `tensor_file` container (Mitsuba's TensorFile, used by the RGL-EPFL `.bsdf` files):
//   the 12 bytes "tensor_file\0", version bytes 1, 0, uint32 field count, then per field
//   uint16 name length, name, uint16 ndim, uint8 dtype, uint64 byte offset, ndim × uint64 shape;
//   every number little-endian. Field data lies anywhere in the file at its offset.
// Opening a file parses and bounds-checks the whole field table; field data is read on request,
// so a large file costs only the fields the caller asks for.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace brdfz::rgl::detail {

enum class DType : std::uint8_t { U8 = 1, I8, U16, I16, U32, I32, U64, I64, F16, F32, F64 };

const char* dtype_name(DType t);

struct Field {
    std::string name;
    DType dtype = DType::U8;
    std::uint64_t offset = 0;
    std::vector<std::uint64_t> shape;
    std::uint64_t count = 1;  // product of shape; count × element size fits in the file
};

class TensorFile {
public:
    // Bounds on the field table, checked before anything is allocated for it. Real files have
    // about a dozen fields of rank ≤ 5 with short names.
    static constexpr std::uint32_t kMaxFields = 1024;
    static constexpr std::uint16_t kMaxNameLength = 1024;
    static constexpr std::uint16_t kMaxRank = 16;

    // IoError when the file cannot be opened or read, FormatError when it is not a valid
    // tensor_file (bad magic or version, truncated table, a field outside the file, duplicates).
    explicit TensorFile(std::string path);

    const std::string& path() const { return path_; }
    const std::vector<Field>& fields() const { return fields_; }
    const Field* find(std::string_view name) const;  // nullptr when absent

    // A field's elements, converted from little-endian; FormatError if the dtype is not the one named.
    std::vector<float> read_f32(const Field& f) const;
    std::vector<std::uint8_t> read_u8(const Field& f) const;

private:
    void read_at(std::uint64_t offset, void* out, std::uint64_t bytes) const;

    std::string path_;
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
    std::uint64_t size_ = 0;
    std::vector<Field> fields_;
};

}  // namespace brdfz::rgl::detail
