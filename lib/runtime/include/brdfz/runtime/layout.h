// The runtime layout (`.brdfzrt`, formats/SPEC.md §6): one material's arrays and its sampler's, flat,
// little-endian, each section 64-byte aligned, so that a CPU maps the file and a GPU uploads its
// sections as they are. The names here are what a reader (brdfz::runtime) and a writer (brdfz export)
// share; SPEC.md documents every section.
#pragma once

#include <cstdint>

namespace brdfz::runtime::layout {

constexpr unsigned char kMagic[8] = {0x89, 'B', 'Z', 'R', 'T', '\r', '\n', 0x1A};
// The newest version this runtime reads. A writer puts the lowest version whose sections a file uses
// (2: HWRP), so that a version-1 reader still opens what it can read whole and refuses the rest by
// number instead of misreading it.
constexpr std::uint32_t kVersion = 2;
constexpr std::uint32_t kHeaderBytes = 64;
constexpr std::uint32_t kSectionBytes = 32;
constexpr std::uint32_t kAlign = 64;
constexpr std::uint32_t kMaxSections = 4096;
constexpr std::uint32_t kMaxObjects = 4097;  // the root and up to 4096 φh slices

// Header, at byte 0 (64 bytes):
//   0 magic[8]   8 u32 version   12 u32 header bytes (64)   16 u64 file size   24 u32 section count
//   28 u32 CRC-32C of bytes [64, file size)   32 u32 root kind   36 u32 objects   40..63 zero
// Section table, at byte 64 (32 bytes each):
//   0 u32 tag   4 u32 dtype   8 u64 offset (a multiple of 64)   16 u64 count (elements)
//   24 u32 object (0: the root; k: φh slice k − 1)   28 u32 zero

enum class Kind : std::uint32_t { Table = 1, Factored = 2, Analytic = 3, PhiH = 4 };
enum class DType : std::uint32_t { U8 = 1, U16 = 2, U32 = 3, I32 = 4, F16 = 5, F32 = 6, F64 = 7 };

inline constexpr std::uint32_t dtype_bytes(DType t) {
    switch (t) {
        case DType::U8: return 1;
        case DType::U16: case DType::F16: return 2;
        case DType::U32: case DType::I32: case DType::F32: return 4;
        case DType::F64: return 8;
    }
    return 0;
}

// A section's tag: four ASCII characters, the first in the lowest byte.
constexpr std::uint32_t tag(const char (&s)[5]) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(s[0])) |
           static_cast<std::uint32_t>(static_cast<unsigned char>(s[1])) << 8 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(s[2])) << 16 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(s[3])) << 24;
}

// Every object.
constexpr std::uint32_t kKind = tag("KIND");  // i32[1]: Kind
constexpr std::uint32_t kDesc = tag("DESC");  // u8[n]: what the material is, for people (root only)
// Gridded kinds.
constexpr std::uint32_t kGrid = tag("GRID");  // i32[6]: nθh, nθd, nφd, centre (1) or start (0), φd axis, lookup
constexpr std::uint32_t kWarp = tag("WARP");  // f64[1]: θd warp
constexpr std::uint32_t kThetaHWarp = tag("HWRP");  // f64[1]: θh warp (radians), only on a warped θh axis
// Tables.
constexpr std::uint32_t kValuesF32 = tag("VF32");  // f32[bins·3]
constexpr std::uint32_t kValuesF16 = tag("VF16");  // f16[bins·3]
constexpr std::uint32_t kHalfScale = tag("SC16");  // f32[3]
constexpr std::uint32_t kValuesU8 = tag("VU8L");   // u8[bins·3]
constexpr std::uint32_t kLut = tag("LUT8");        // f32[3·256]
// Factorisations.
constexpr std::uint32_t kFactorParams = tag("FPAR");  // i32[4]: layout, space, colour, rank
constexpr std::uint32_t kFactorMax = tag("FMAX");     // f32[3]
constexpr std::uint32_t kFactorU = tag("FACU");       // f32 or f16 [rows·m]
constexpr std::uint32_t kFactorV = tag("FACV");       // f32 or f16 [columns·m]
constexpr std::uint32_t kFactorColour = tag("FCOL");  // f32[3·rank], shared colour only
// Analytic models.
constexpr std::uint32_t kModel = tag("MODL");   // u8[n]: the lobe families joined by '+', e.g. "lambert+ggx"
constexpr std::uint32_t kParams = tag("PRMS");  // f64[k]
constexpr std::uint32_t kAlbedo = tag("ALBD");  // f64[16·terms]: the lobe mixture's albedo table
// φh stacks.
constexpr std::uint32_t kPhiH = tag("PHIH");  // i32[2]: symmetry (0 none, 1 reciprocal, 2 bilateral), slices
// The compact sampler (kernels/compact_sampler.h).
constexpr std::uint32_t kSamplerShape = tag("SAMP");   // i32[3]: slices, rows, cols
constexpr std::uint32_t kSamplerParams = tag("SPRM");  // f64[2]: cos_theta_max, cosine_share
constexpr std::uint32_t kSamplerEdges = tag("SEDG");   // f32[rows + 1]
constexpr std::uint32_t kSamplerRows = tag("SROW");    // u32[slices·rows]
constexpr std::uint32_t kSamplerCols = tag("SCOL");    // u16[slices·rows·cols]
constexpr std::uint32_t kSamplerWeights = tag("SEWT");  // f16[slices·(rows + 1)]

// GRID's φd axis and lookup codes.
constexpr std::int32_t kPhiDReciprocal = 0, kPhiDNone = 1, kPhiDBilateral = 2;
constexpr std::int32_t kLookupLinear = 0, kLookupNearest = 1;
// FPAR's codes.
constexpr std::int32_t kLayoutHxDP = 0, kLayoutHDxP = 1;
constexpr std::int32_t kSpaceLinear = 0, kSpaceCos = 1, kSpaceLog = 2, kSpaceCbrt = 3;
constexpr std::int32_t kColourSeparate = 0, kColourShared = 1;

}  // namespace brdfz::runtime::layout
