// brdfz::runtime. Its calls are compiled for each Highway target (hwy/foreach_target.h includes this file
// again for each; hwy_dispatch.h picks one when a material opens), the rest once.
#ifndef BRDFZ_RUNTIME_ONCE
#define BRDFZ_RUNTIME_ONCE
#include "brdfz/runtime/runtime.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <type_traits>
#include <map>
#include <utility>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#define BRDFZ_RUNTIME_MMAP 1
#endif

#include "brdfz/runtime/crc32c.h"
#include "brdfz/runtime/kernels/compact_sampler.h"
#include "brdfz/runtime/kernels/factored.h"
#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/lobe_mixture.h"
#include "brdfz/runtime/kernels/phi_h.h"
#include "brdfz/runtime/kernels/simd.h"
#include "brdfz/runtime/kernels/values.h"
#include "brdfz/runtime/layout.h"
#include "factored_calls.h"
#include "hwy_dispatch.h"

namespace brdfz::runtime {
namespace detail {

namespace k = kernels;
namespace L = layout;

// One material object: the root, or a φh stack's slice.
struct Object {
    L::Kind kind = L::Kind::Table;
    // Tables and factorisations.
    k::Grid grid;
    bool nearest = false;
    // Tables: one of the three value kinds.
    const float* f32 = nullptr;
    const std::uint8_t* codes = nullptr;  // f16 (2 bytes a channel) or u8
    bool half = false;
    std::array<float, 3> half_scale{};
    const float* lut = nullptr;
    // Factorisations: the view's padded float rows and mix live in `factor_data`; their eval is the
    // build of the material's level (factored_calls.h).
    k::FactorView factors;
    std::vector<float> factor_data;
    FactoredEvalFn* factored_eval = nullptr;
    // φh stacks: slices [first, first + count) of Data::slices.
    bool bilateral = false;
    std::size_t first = 0, count = 0;
    // Analytic models: the terms, the parameters and the lobe mixture's albedo table.
    std::vector<k::LobeTerm> terms;
    k::LobeMixtureView lobes;
};

struct Data {
    std::vector<unsigned char> owned;
    const unsigned char* bytes = nullptr;
    std::size_t size = 0;
    void* mapped = nullptr;
    std::string describe;
    Simd level = Simd::Sse2;  // the kernels' builds, taken when the material is parsed
    Object root;
    std::vector<Object> slices;
    bool has_sampler = false;
    k::CompactSamplerView sampler;
    std::size_t sampler_bytes = 0;

    Data() = default;
    Data(const Data&) = delete;
    Data& operator=(const Data&) = delete;
    ~Data() {
#ifdef BRDFZ_RUNTIME_MMAP
        if (mapped) munmap(mapped, size);
#endif
    }
};

namespace {

template <typename T>
T read_le(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);  // the layout is little-endian, as every platform brdfz builds on
    return v;
}

struct Section {
    L::DType dtype;
    std::uint64_t offset, count;
};

struct Failure {
    std::string what;
};
[[noreturn]] void fail(const std::string& what) { throw Failure{what}; }

// The sections of one object, by tag, with typed access that checks dtype and count.
class Sections {
public:
    Sections(const Data& d, std::map<std::uint32_t, Section> s, std::uint32_t object)
        : d_(d), s_(std::move(s)), object_(object) {}

    bool has(std::uint32_t tag) const { return s_.count(tag) != 0; }
    template <typename T>
    const T* get(std::uint32_t tag, L::DType dtype, std::uint64_t count) const {
        const auto it = s_.find(tag);
        if (it == s_.end()) fail(where(tag) + " is missing");
        if (it->second.dtype != dtype) fail(where(tag) + " has the wrong element type");
        if (it->second.count != count)
            fail(where(tag) + " holds " + std::to_string(it->second.count) + " elements, expected " + std::to_string(count));
        return reinterpret_cast<const T*>(d_.bytes + it->second.offset);
    }
    const Section* find(std::uint32_t tag) const {
        const auto it = s_.find(tag);
        return it == s_.end() ? nullptr : &it->second;
    }
    std::string where(std::uint32_t tag) const {
        char name[5] = {static_cast<char>(tag & 0xFF), static_cast<char>(tag >> 8 & 0xFF),
                        static_cast<char>(tag >> 16 & 0xFF), static_cast<char>(tag >> 24 & 0xFF), 0};
        for (char& c : name)
            if (c && (c < 32 || c > 126)) c = '?';
        return "section " + std::string(name) + (object_ ? " of slice " + std::to_string(object_ - 1) : "");
    }

private:
    const Data& d_;
    std::map<std::uint32_t, Section> s_;
    std::uint32_t object_;
};

std::int32_t one_int(const Sections& s, std::uint32_t tag) { return *s.get<std::int32_t>(tag, L::DType::I32, 1); }

void read_grid(const Sections& s, Object& o) {
    const std::int32_t* g = s.get<std::int32_t>(L::kGrid, L::DType::I32, 6);
    for (int i = 0; i < 3; ++i)
        if (g[i] < 1 || g[i] > 4096) fail(s.where(L::kGrid) + ": a grid axis is outside 1..4096");
    if (static_cast<std::uint64_t>(g[0]) * g[1] * g[2] > (std::uint64_t{1} << 26)) fail(s.where(L::kGrid) + ": more than 2^26 bins");
    if (g[3] != 0 && g[3] != 1) fail(s.where(L::kGrid) + ": bin position is neither 0 nor 1");
    if (g[4] < 0 || g[4] > 2) fail(s.where(L::kGrid) + ": unknown φd axis");
    if (g[5] != L::kLookupLinear && g[5] != L::kLookupNearest) fail(s.where(L::kGrid) + ": unknown lookup");
    o.grid.n_theta_h = g[0], o.grid.n_theta_d = g[1], o.grid.n_phi_d = g[2];
    o.grid.centre = g[3] == 1;
    o.grid.phi_d_axis = static_cast<k::Grid::Axis>(g[4]);
    o.nearest = g[5] == L::kLookupNearest;
    const double w = *s.get<double>(L::kWarp, L::DType::F64, 1);
    if (!(w >= 0.0 && w <= 0.95)) fail(s.where(L::kWarp) + ": θd warp outside [0, 0.95]");
    o.grid.theta_d_warp = w;
    if (s.has(L::kThetaHWarp)) {
        const double h = *s.get<double>(L::kThetaHWarp, L::DType::F64, 1);
        // GridSpec::kMinThetaHWarp, kMaxThetaHWarp: 0.01° to 45°.
        if (!(h >= 0.01 * k::kPi / 180.0 && h <= k::kPi / 4.0)) fail(s.where(L::kThetaHWarp) + ": θh warp outside [0.01°, 45°]");
        o.grid.theta_h_warp = h;
    }
}

void read_table(const Sections& s, Object& o) {
    read_grid(s, o);
    const std::uint64_t n = 3 * static_cast<std::uint64_t>(o.grid.bins());
    std::size_t valid = 0;
    if (s.has(L::kValuesF32)) {
        o.f32 = s.get<float>(L::kValuesF32, L::DType::F32, n);
        for (std::uint64_t i = 0; i < n; ++i) {
            const float v = o.f32[i];
            if (v != v) continue;
            if (!(v >= 0.0f && v <= std::numeric_limits<float>::max())) fail(s.where(L::kValuesF32) + ": a value is negative or infinite");
            ++valid;
        }
    } else if (s.has(L::kValuesF16)) {
        o.half = true;
        o.codes = s.get<std::uint8_t>(L::kValuesF16, L::DType::F16, n);
        const float* scale = s.get<float>(L::kHalfScale, L::DType::F32, 3);
        for (int c = 0; c < 3; ++c) {
            if (!(scale[c] > 0.0f && std::isfinite(scale[c]))) fail(s.where(L::kHalfScale) + ": a scale is not a finite value > 0");
            o.half_scale[c] = scale[c];
        }
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::uint16_t h = read_le<std::uint16_t>(o.codes + 2 * i);
            if (h == k::HalfValues::kInvalid) continue;
            if ((h & 0x8000u) || (h & 0x7c00u) == 0x7c00u) fail(s.where(L::kValuesF16) + ": a code is negative, infinite or NaN");
            ++valid;
        }
    } else {
        o.codes = s.get<std::uint8_t>(L::kValuesU8, L::DType::U8, n);
        o.lut = s.get<float>(L::kLut, L::DType::F32, 3 * 256);
        for (int c = 0; c < 3; ++c)
            for (int q = 0; q < 255; ++q)
                if (!(o.lut[256 * c + q] >= 0.0f && o.lut[256 * c + q] <= std::numeric_limits<float>::max()))
                    fail(s.where(L::kLut) + ": a decoded value is negative, infinite or NaN");
        for (std::uint64_t i = 0; i < n; ++i) valid += o.codes[i] != 255 ? 1 : 0;
    }
    if (valid == 0) fail("the table holds no value");
}

void read_factored(const Sections& s, Object& o, Simd level) {
    read_grid(s, o);
    const std::int32_t* p = s.get<std::int32_t>(L::kFactorParams, L::DType::I32, 4);
    k::FactorView& f = o.factors;
    f.grid = o.grid;
    if (p[0] != L::kLayoutHxDP && p[0] != L::kLayoutHDxP) fail(s.where(L::kFactorParams) + ": unknown layout");
    if (p[1] < L::kSpaceLinear || p[1] > L::kSpaceCbrt) fail(s.where(L::kFactorParams) + ": unknown space");
    if (p[2] != L::kColourSeparate && p[2] != L::kColourShared) fail(s.where(L::kFactorParams) + ": unknown colour");
    f.layout = p[0], f.space = p[1];
    const bool shared = p[2] == L::kColourShared;
    const std::uint64_t rows = f.layout == L::kLayoutHxDP ? o.grid.n_theta_h : std::uint64_t(o.grid.n_theta_h) * o.grid.n_theta_d;
    const std::uint64_t cols = f.layout == L::kLayoutHxDP ? std::uint64_t(o.grid.n_theta_d) * o.grid.n_phi_d : o.grid.n_phi_d;
    if (p[3] < 1 || static_cast<std::uint64_t>(p[3]) > std::min(rows, cols)) fail(s.where(L::kFactorParams) + ": rank out of range");
    const int rank = p[3];
    const std::uint64_t m = shared ? rank : 3 * static_cast<std::uint64_t>(rank);
    const bool grouped = !shared && (rank == 3 || rank == 4);
    // Component j's column in the padded rows (see FactorView).
    const auto column = [&](std::uint64_t j) { return grouped ? 4 * (j / rank) + j % rank : j; };
    // Each factor's entries (float16 or float), their sizes checked before anything is allocated.
    struct Source {
        const std::uint8_t* half;
        const float* single;
    };
    const auto source = [&](std::uint32_t tag, std::uint64_t n) -> Source {
        const Section* x = s.find(tag);
        if (x && x->dtype == L::DType::F16) return {s.get<std::uint8_t>(tag, L::DType::F16, n * m), nullptr};
        return {nullptr, s.get<float>(tag, L::DType::F32, n * m)};
    };
    const Source us = source(L::kFactorU, rows), vs = source(L::kFactorV, cols);
    const std::uint64_t lanes = k::factor_lanes(level);
    f.width = ((grouped ? 12 : m) + lanes - 1) / lanes * lanes;
    f.grouped = grouped;
    o.factored_eval = factored_eval_build(level);
    const std::uint64_t w = f.width;
    o.factor_data.assign((rows + cols + 3) * w, 0.0f);
    float* const u = o.factor_data.data();
    float* const v = u + rows * w;
    float* const mix = v + cols * w;
    // The entries, float16 widened to float, in their padded columns. Every reconstruction is bounded by
    // the components' largest magnitudes: within a quarter of the float range, as the library requires,
    // no partial sum overflows.
    const auto widen = [&](const Source& from, std::uint64_t n, float* out, std::vector<double>& top) {
        top.assign(m, 0.0);
        for (std::uint64_t i = 0; i < n * m; ++i) {
            const float e = from.half ? k::half_to_float(read_le<std::uint16_t>(from.half + 2 * i)) : from.single[i];
            if (!std::isfinite(e)) fail("a factor entry is not finite");
            top[i % m] = std::max(top[i % m], std::fabs(double{e}));
            out[i / m * w + column(i % m)] = e;
        }
    };
    std::vector<double> top_u, top_v;
    widen(us, rows, u, top_u);
    widen(vs, cols, v, top_v);
    f.u = u, f.v = v, f.mix = mix;
    const float* colour = shared ? s.get<float>(L::kFactorColour, L::DType::F32, 3 * static_cast<std::uint64_t>(rank)) : nullptr;
    const float* top = s.get<float>(L::kFactorMax, L::DType::F32, 3);
    for (int c = 0; c < 3; ++c) {
        double bound = 0.0;
        for (int j = 0; j < rank; ++j) {
            const float weight = shared ? colour[c * rank + j] : 1.0f;
            if (!std::isfinite(weight)) fail("a colour weight is not finite");
            const std::uint64_t at = shared ? j : static_cast<std::uint64_t>(c) * rank + j;
            bound += std::fabs(double{weight}) * top_u[at] * top_v[at];
            mix[c * w + column(at)] = weight;
        }
        if (!(bound <= 0.25 * std::numeric_limits<float>::max())) fail("the factors reconstruct values beyond the float range");
        if (!(top[c] >= 0.0f)) fail(s.where(L::kFactorMax) + ": a ceiling is NaN or negative");
        const double t = std::min(top[c], std::numeric_limits<float>::max());
        f.ceiling[c] = static_cast<float>(f.space == L::kSpaceLog ? std::log1p(t) : f.space == L::kSpaceCbrt ? std::cbrt(t) : t);
    }
}

void read_analytic(const Sections& s, Object& o) {
    const Section* text = s.find(L::kModel);
    if (!text || text->dtype != L::DType::U8 || text->count == 0 || text->count > 4096) fail(s.where(L::kModel) + " is missing or malformed");
    const std::string model = std::string(s.get<char>(L::kModel, L::DType::U8, text->count), text->count);
    std::size_t params = 0;
    for (std::size_t at = 0; at <= model.size();) {
        const std::size_t plus = std::min(model.find('+', at), model.size());
        const int family = k::lobe_family(std::string_view(model).substr(at, plus - at));
        if (family < 0) fail("unknown lobe family '" + model.substr(at, plus - at) + "'");
        if (o.terms.size() == k::kMaxLobeTerms) fail("more than " + std::to_string(k::kMaxLobeTerms) + " lobes");
        o.terms.push_back({family, params});
        params += k::kLobeFamilies[family].params;
        at = plus + 1;
    }
    const double* p = s.get<double>(L::kParams, L::DType::F64, params);
    for (const k::LobeTerm& t : o.terms) {
        const k::LobeFamily& f = k::kLobeFamilies[t.family];
        for (std::size_t i = 0; i < f.params; ++i)
            if (!(p[t.offset + i] >= f.specs[i].lo && p[t.offset + i] <= f.specs[i].hi))
                fail("parameter " + std::string(f.name) + "." + std::string(f.specs[i].name) + " outside its bounds");
    }
    // The lobe mixture's table, for a model without a compact sampler (parse checks that it has one).
    const double* albedo = nullptr;
    if (s.find(L::kAlbedo)) {
        albedo = s.get<double>(L::kAlbedo, L::DType::F64, k::kAlbedoNodes * o.terms.size());
        for (std::size_t i = 0; i < k::kAlbedoNodes * o.terms.size(); ++i)
            if (!(albedo[i] >= 0.0 && albedo[i] < std::numeric_limits<double>::infinity())) fail("an albedo is negative or not finite");
    }
    o.lobes = {o.terms.data(), o.terms.size(), p, albedo};
}

// The compact sampler's sections, checked as the library checks its tables.
void read_sampler(const Sections& s, Data& d) {
    const std::int32_t* shape = s.get<std::int32_t>(L::kSamplerShape, L::DType::I32, 3);
    if (shape[0] < 2 || shape[0] > 1024 || shape[1] < 1 || shape[1] > 4096 || shape[2] < 1 || shape[2] > 4096)
        fail(s.where(L::kSamplerShape) + ": slices, rows or cols out of range");
    const std::uint64_t K = shape[0], R = shape[1], C = shape[2];
    const double* params = s.get<double>(L::kSamplerParams, L::DType::F64, 2);
    k::CompactSamplerView v;
    v.slices = shape[0], v.rows = shape[1], v.cols = shape[2];
    v.cos_theta_max = params[0], v.cosine_share = params[1];
    v.s_edges = s.get<float>(L::kSamplerEdges, L::DType::F32, R + 1);
    v.row_cdf = s.get<std::uint32_t>(L::kSamplerRows, L::DType::U32, K * R);
    v.col_cdf = s.get<std::uint16_t>(L::kSamplerCols, L::DType::U16, K * R * C);
    v.edge_weight = s.get<std::uint16_t>(L::kSamplerWeights, L::DType::F16, K * (R + 1));
    if (const char* why = k::check_compact_sampler(v)) fail("the sampler's tables: " + std::string(why));
    d.sampler = v;
    d.has_sampler = true;
    d.sampler_bytes = (R + 1) * 4 + K * R * 4 + K * R * C * 2 + K * (R + 1) * 2 + 12 + 16;
}

void parse(Data& d) {
    const unsigned char* b = d.bytes;
    d.level = k::simd_level();
    if (d.size < L::kHeaderBytes || std::memcmp(b, L::kMagic, 8) != 0) fail("not a brdfz runtime layout");
    const std::uint32_t version = read_le<std::uint32_t>(b + 8);
    if (version < 1 || version > L::kVersion)
        fail("layout version " + std::to_string(version) + ", this runtime reads versions 1 to " + std::to_string(L::kVersion));
    if (read_le<std::uint32_t>(b + 12) != L::kHeaderBytes) fail("unexpected header size");
    if (read_le<std::uint64_t>(b + 16) != d.size)
        fail("the header says " + std::to_string(read_le<std::uint64_t>(b + 16)) + " bytes, the data has " + std::to_string(d.size));
    const std::uint32_t n = read_le<std::uint32_t>(b + 24);
    if (n > L::kMaxSections || L::kHeaderBytes + std::uint64_t(n) * L::kSectionBytes > d.size) fail("the section table does not fit");
    if (crc32c(b + L::kHeaderBytes, d.size - L::kHeaderBytes) != read_le<std::uint32_t>(b + 28)) fail("checksum mismatch (damaged data)");
    const std::uint32_t objects = read_le<std::uint32_t>(b + 36);
    if (objects < 1 || objects > L::kMaxObjects) fail("object count out of range");
    std::vector<std::map<std::uint32_t, Section>> by_object(objects);
    const std::uint64_t data_start = L::kHeaderBytes + std::uint64_t(n) * L::kSectionBytes;
    for (std::uint32_t i = 0; i < n; ++i) {
        const unsigned char* e = b + L::kHeaderBytes + std::size_t(i) * L::kSectionBytes;
        const std::uint32_t tag = read_le<std::uint32_t>(e), dtype = read_le<std::uint32_t>(e + 4);
        const std::uint64_t offset = read_le<std::uint64_t>(e + 8), count = read_le<std::uint64_t>(e + 16);
        const std::uint32_t object = read_le<std::uint32_t>(e + 24);
        const std::uint32_t size = dtype >= 1 && dtype <= 7 ? L::dtype_bytes(static_cast<L::DType>(dtype)) : 0;
        if (!size) fail("section " + std::to_string(i) + " has an unknown element type");
        if (object >= objects) fail("section " + std::to_string(i) + " belongs to no object");
        if (offset % L::kAlign || offset < data_start || offset > d.size || count > (d.size - offset) / size)
            fail("section " + std::to_string(i) + " lies outside the data");
        if (!by_object[object].emplace(tag, Section{static_cast<L::DType>(dtype), offset, count}).second)
            fail("section " + std::to_string(i) + " repeats a tag");
        if (tag == L::kThetaHWarp && version < 2) fail("section HWRP in a version-1 layout (it needs version 2)");
    }
    const Sections root(d, by_object[0], 0);
    if (const Section* desc = root.find(L::kDesc); desc && desc->dtype == L::DType::U8)
        d.describe.assign(reinterpret_cast<const char*>(b + desc->offset), desc->count);
    const auto kind_of = [&](const Sections& s) {
        const std::int32_t kind = one_int(s, L::kKind);
        if (kind < 1 || kind > 4) fail("unknown kind " + std::to_string(kind));
        return static_cast<L::Kind>(kind);
    };
    d.root.kind = kind_of(root);
    if (static_cast<std::uint32_t>(d.root.kind) != read_le<std::uint32_t>(b + 32)) fail("the header's kind is not the root's");
    const auto read_object = [&](const Sections& s, Object& o) {
        switch (o.kind) {
            case L::Kind::Table: return read_table(s, o);
            case L::Kind::Factored: return read_factored(s, o, d.level);
            case L::Kind::Analytic: return read_analytic(s, o);
            case L::Kind::PhiH: fail("a φh slice cannot be a stack");
        }
    };
    if (d.root.kind == L::Kind::PhiH) {
        const std::int32_t* p = root.get<std::int32_t>(L::kPhiH, L::DType::I32, 2);
        if (p[0] < 0 || p[0] > 2) fail("unknown φh symmetry");
        if (p[1] < 2 || p[1] > 4096 || static_cast<std::uint32_t>(p[1]) + 1 != objects) fail("φh slice count disagrees with the objects");
        d.root.bilateral = p[0] == 2;
        d.root.first = 0, d.root.count = static_cast<std::size_t>(p[1]);
        d.slices.resize(d.root.count);
        for (std::size_t i = 0; i < d.root.count; ++i) {
            const Sections s(d, by_object[i + 1], static_cast<std::uint32_t>(i + 1));
            d.slices[i].kind = kind_of(s);
            read_object(s, d.slices[i]);
        }
    } else {
        if (objects != 1) fail("objects beyond the root of a material without φh slices");
        read_object(root, d.root);
    }
    // Every kind but an analytic model carries the compact sampler; a model without one samples its lobes.
    if (d.root.kind != L::Kind::Analytic || root.find(L::kSamplerShape)) read_sampler(root, d);
    if (!d.has_sampler && !d.root.lobes.albedo) fail(root.where(L::kAlbedo) + " is missing: an analytic model without a sampler needs it");
}

std::shared_ptr<const Data> parsed(std::unique_ptr<Data> d, std::string* error) {
    try {
        parse(*d);
        return std::shared_ptr<const Data>(std::move(d));
    } catch (const Failure& f) {
        if (error) *error = f.what;
    } catch (const std::bad_alloc&) {
        if (error) *error = "out of memory";
    }
    return nullptr;
}

// The evaluators of one kind of object, for a pair above the horizon (eval<Blend>(o, wi, wo, f); Blend:
// a table's blend across channels, grid.h's ScalarBlend or a target's BlendLanes). Each call table
// below is built for one of them, so that a material's calls hold only its own kind's code.
template <typename Values, bool Nearest>
struct TableLeaf {
    static Values values(const Object& o) {
        if constexpr (std::is_same_v<Values, k::Float32Values>) return {o.f32};
        else if constexpr (std::is_same_v<Values, k::HalfValues>) return {o.codes, o.half_scale};
        else return {o.codes, o.lut};
    }
    template <typename Blend>
    static void eval(const Object& o, const Vec3& wi, const Vec3& wo, double f[3]) {
        const k::BinCoords c = k::fast_bin_coords(o.grid, wi, wo);
        if constexpr (Nearest)
            k::read_nearest(values(o), k::nearest_bin(o.grid, c, wi, wo), f);
        else
            Blend::blend(o.grid, values(o), k::linear_corners(o.grid, c, wi, wo), f);
    }
};
struct FactoredLeaf {
    template <typename Blend>
    static void eval(const Object& o, const Vec3& wi, const Vec3& wo, double f[3]) { o.factored_eval(o.factors, wi, wo, f); }
};
struct LobesLeaf {
    template <typename Blend>
    static void eval(const Object& o, const Vec3& wi, const Vec3& wo, double f[3]) { k::lobe_mixture_eval(o.lobes, wi, wo, f); }
};
// Any object but a φh stack (the slices of one).
struct AnyLeaf {
    template <typename Blend, bool Nearest>
    static void table(const Object& o, const Vec3& wi, const Vec3& wo, double f[3]) {
        if (o.f32) return TableLeaf<k::Float32Values, Nearest>::template eval<Blend>(o, wi, wo, f);
        if (o.half) return TableLeaf<k::HalfValues, Nearest>::template eval<Blend>(o, wi, wo, f);
        return TableLeaf<k::LogU8Values, Nearest>::template eval<Blend>(o, wi, wo, f);
    }
    template <typename Blend>
    static void eval(const Object& o, const Vec3& wi, const Vec3& wo, double f[3]) {
        switch (o.kind) {
            case L::Kind::Table: return o.nearest ? table<Blend, true>(o, wi, wo, f) : table<Blend, false>(o, wi, wo, f);
            case L::Kind::Factored: return FactoredLeaf::eval<Blend>(o, wi, wo, f);
            case L::Kind::Analytic: return LobesLeaf::eval<Blend>(o, wi, wo, f);
            case L::Kind::PhiH: break;  // never a slice: parse refuses stacks of stacks
        }
        f[0] = f[1] = f[2] = 0.0;
    }
};

// f of the root for a pair above the horizon; Leaf evaluates the root, or a φh stack's slices.
template <typename Leaf, typename Blend>
void eval_root(const Data& d, const Vec3& wi, const Vec3& wo, double f[3]) {
    const Object& o = d.root;
    if (o.kind != L::Kind::PhiH) return Leaf::template eval<Blend>(o, wi, wo, f);
    const k::PhiHPick pick = k::phi_h_pick(o.bilateral, o.count, wi, wo);
    f[0] = f[1] = f[2] = 0.0;
    if (!pick.ok) return;
    Vec3 a = wi, b = wo;
    if (pick.mirrored) a.y = -a.y, b.y = -b.y;
    double x[3], y[3];
    // Slices are tables or factorisations, whose own eval is 0 below the horizon (never here).
    Leaf::template eval<Blend>(d.slices[o.first + pick.k0], a, b, x);
    Leaf::template eval<Blend>(d.slices[o.first + pick.k1], a, b, y);
    for (int c = 0; c < 3; ++c) f[c] = x[c] * (1.0 - pick.t) + y[c] * pick.t;
}

// The calls on prepared directions (Calls' contract).
template <typename Leaf, typename Blend = k::ScalarBlend>
Rgb64 eval64(const Data* d, const Vec3& wi, const Vec3& wo) noexcept {
    Rgb64 f;
    eval_root<Leaf, Blend>(*d, wi, wo, f.data());
    return f;
}

double pdf64(const Data* d, const Vec3& wo, const Vec3& wi) noexcept {
    if (!d->has_sampler) return k::lobe_mixture_pdf(d->root.lobes, wo, wi);
    return k::compact_pdf(d->sampler, wo, wi);
}

template <typename Leaf, typename Blend>
Sample64 sample64(const Data* d, const Vec3& wo, double u1, double u2) noexcept {
    Sample64 s;
    if (!d->has_sampler) {
        const k::LobeMixtureDraw draw = k::lobe_mixture_sample(d->root.lobes, wo, u1, u2);
        s.wi = draw.wi, s.pdf = draw.pdf;
    } else {
        const k::CompactDraw draw = k::compact_sample(d->sampler, wo, u1, u2);
        s.wi = draw.wi, s.pdf = draw.pdf;
    }
    if (!(s.wi.z > 0.0 && s.pdf > 0.0 && s.pdf < std::numeric_limits<double>::infinity())) return {};
    double f[3];
    eval_root<Leaf, Blend>(*d, s.wi, wo, f);
    for (int c = 0; c < 3; ++c) s.weight[c] = f[c] * s.wi.z / s.pdf;  // the library's arithmetic
    return s;
}

}  // namespace
}  // namespace detail
}  // namespace brdfz::runtime
#endif  // BRDFZ_RUNTIME_ONCE

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "runtime.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "blend_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace brdfz::runtime::detail::HWY_NAMESPACE {

// The calls for the target, each flattened into one body of its kind's code: the lookups and the
// sampler run faster in the wider builds (as the library's one-pair table call); without FMA they give
// the baseline's bits. A factorisation's eval is its own build's (factored_calls.h), the library's to
// the bit.
using Blend = kernels::HWY_NAMESPACE::BlendLanes;
template <typename Leaf>
[[gnu::flatten]] Rgb64 Eval(const Data* d, const Vec3& wi, const Vec3& wo) noexcept {
    return eval64<Leaf, Blend>(d, wi, wo);
}
[[gnu::flatten]] double Pdf(const Data* d, const Vec3& wo, const Vec3& wi) noexcept { return pdf64(d, wo, wi); }
template <typename Leaf>
[[gnu::flatten]] Sample64 Sample(const Data* d, const Vec3& wo, double u1, double u2) noexcept {
    return sample64<Leaf, Blend>(d, wo, u1, u2);
}

}  // namespace brdfz::runtime::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace brdfz::runtime {
namespace detail {
namespace {

// The calls of one kind at each level. An analytic model's eval is not flattened: its lobe mixture,
// every family inlined into one body, runs slower.
template <typename Leaf>
const Calls* calls_of(Simd level) {
    static const auto eval = BRDFZ_HWY_BUILDS(Eval<Leaf>);
    static const auto pdf = BRDFZ_HWY_BUILDS(Pdf);
    static const auto sample = BRDFZ_HWY_BUILDS(Sample<Leaf>);
    static const auto at = [](Simd s) {
        return Calls{std::is_same_v<Leaf, LobesLeaf> ? eval64<Leaf> : eval.at(s), pdf.at(s), sample.at(s)};
    };
    static const Calls calls[] = {at(Simd::Sse2), at(Simd::Avx2Fma), at(Simd::Avx512)};
    return &calls[static_cast<int>(level)];
}

// The call table of the root's kind (a φh stack's: its slices' kind, where they share one).
const Calls* calls_for(const Data& d) {
    const Object* o = &d.root;
    if (o->kind == L::Kind::PhiH) {
        for (const Object& slice : d.slices)
            if (slice.kind != d.slices[0].kind || (slice.f32 != nullptr) != (d.slices[0].f32 != nullptr) ||
                slice.half != d.slices[0].half || slice.nearest != d.slices[0].nearest)
                return calls_of<AnyLeaf>(d.level);
        o = &d.slices[0];
    }
    switch (o->kind) {
        case L::Kind::Factored: return calls_of<FactoredLeaf>(d.level);
        case L::Kind::Analytic: return calls_of<LobesLeaf>(d.level);
        case L::Kind::Table:
            if (o->f32) return o->nearest ? calls_of<TableLeaf<k::Float32Values, true>>(d.level) : calls_of<TableLeaf<k::Float32Values, false>>(d.level);
            if (o->half) return o->nearest ? calls_of<TableLeaf<k::HalfValues, true>>(d.level) : calls_of<TableLeaf<k::HalfValues, false>>(d.level);
            return o->nearest ? calls_of<TableLeaf<k::LogU8Values, true>>(d.level) : calls_of<TableLeaf<k::LogU8Values, false>>(d.level);
        case L::Kind::PhiH: break;
    }
    return calls_of<AnyLeaf>(d.level);
}

Rgb64 no_eval(const Data*, const Vec3&, const Vec3&) noexcept { return {0.0, 0.0, 0.0}; }
double no_pdf(const Data*, const Vec3&, const Vec3&) noexcept { return 0.0; }
Sample64 no_sample(const Data*, const Vec3&, double, double) noexcept { return {}; }

}  // namespace

const Calls kNoCalls{no_eval, no_pdf, no_sample};

}  // namespace detail

Material::Material(std::shared_ptr<const detail::Data> d)
    : d_(std::move(d)), calls_(d_ ? detail::calls_for(*d_) : &detail::kNoCalls) {}

Material Material::from_memory(const void* data, std::size_t size, bool copy, std::string* error) {
    auto d = std::make_unique<detail::Data>();
    if (!data) size = 0;
    if (copy) {
        try {
            d->owned.assign(static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + size);
        } catch (const std::bad_alloc&) {
            if (error) *error = "out of memory";
            return {};
        }
        d->bytes = d->owned.data();
    } else {
        // Sections are read in place as arrays of up to 8-byte elements.
        if (reinterpret_cast<std::uintptr_t>(data) % 8 != 0) {
            if (error) *error = "borrowed layout bytes must be 8-byte aligned (copy them instead)";
            return {};
        }
        d->bytes = static_cast<const unsigned char*>(data);
    }
    d->size = size;
    return Material(detail::parsed(std::move(d), error));
}

Material Material::open(const std::string& path, std::string* error) {
    const auto failed = [&](const std::string& why) {
        if (error) *error = path + ": " + why;
        return Material();
    };
#ifdef BRDFZ_RUNTIME_MMAP
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return failed(std::strerror(errno));
    struct stat st {};
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        return failed("not a regular file");
    }
    auto d = std::make_unique<detail::Data>();
    d->size = static_cast<std::size_t>(st.st_size);
    if (d->size > 0) {
        void* p = mmap(nullptr, d->size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (p == MAP_FAILED) {
            ::close(fd);
            return failed(std::strerror(errno));
        }
        d->mapped = p;
        d->bytes = static_cast<const unsigned char*>(p);
    }
    ::close(fd);
#else
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return failed("cannot open");
    auto d = std::make_unique<detail::Data>();
    unsigned char buffer[1 << 16];
    for (std::size_t got; (got = std::fread(buffer, 1, sizeof buffer, file)) > 0;) d->owned.insert(d->owned.end(), buffer, buffer + got);
    std::fclose(file);
    d->bytes = d->owned.data(), d->size = d->owned.size();
#endif
    std::string why;
    Material m(detail::parsed(std::move(d), &why));
    if (!m) return failed(why);
    return m;
}

std::string Material::describe() const { return d_ ? d_->describe : std::string(); }
const void* Material::data() const { return d_ ? d_->bytes : nullptr; }
std::size_t Material::nbytes() const { return d_ ? d_->size : 0; }
std::size_t Material::sampler_nbytes() const { return d_ ? d_->sampler_bytes : 0; }

void Material::eval(const Float3* wi, const Float3* wo, Rgb32* out, std::size_t n) const noexcept {
    for (std::size_t i = 0; i < n; ++i) out[i] = eval(wi[i], wo[i]);
}
void Material::pdf(const Float3* wo, const Float3* wi, float* out, std::size_t n) const noexcept {
    for (std::size_t i = 0; i < n; ++i) out[i] = pdf(wo[i], wi[i]);
}
void Material::sample(const Float3* wo, const float* u, Sample32* out, std::size_t n) const noexcept {
    for (std::size_t i = 0; i < n; ++i) out[i] = sample(wo[i], u[2 * i], u[2 * i + 1]);
}

}  // namespace brdfz::runtime
#endif  // HWY_ONCE
