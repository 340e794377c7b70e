// The runtime layout's writer (formats/SPEC.md §6): each kind's arrays as the library holds them, and
// the compact sampler's, as sections of one flat file.
#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <optional>

#include "brdfz/errors.h"
#include "brdfz/formats/runtime_layout.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/runtime/crc32c.h"
#include "brdfz/runtime/layout.h"
#include "brdfz/select.h"
#include "brdfz/tabulate.h"
#include "brdfzrt/runtime_brdf.h"
#include "detail/atomic_file.h"

namespace brdfz::runtime_layout {
namespace {

namespace L = runtime::layout;

struct Section {
    std::uint32_t tag, object;
    L::DType dtype;
    std::uint64_t count;
    std::vector<unsigned char> bytes;
};

class Builder {
public:
    // `count` elements of `dtype` at `data`, in this machine's order (little-endian, as the layout).
    void add(std::uint32_t tag, std::uint32_t object, L::DType dtype, const void* data, std::size_t count) {
        static_assert(std::endian::native == std::endian::little, "the runtime layout is little-endian");
        Section s{tag, object, dtype, count, std::vector<unsigned char>(count * L::dtype_bytes(dtype))};
        if (count) std::memcpy(s.bytes.data(), data, s.bytes.size());
        sections_.push_back(std::move(s));
    }
    void add_int(std::uint32_t tag, std::uint32_t object, std::initializer_list<std::int32_t> v) {
        add(tag, object, L::DType::I32, v.begin(), v.size());
    }
    void set_objects(std::uint32_t n) { objects_ = n; }

    std::vector<unsigned char> finish(L::Kind root) const {
        const auto align = [](std::uint64_t x) { return (x + L::kAlign - 1) / L::kAlign * L::kAlign; };
        std::uint64_t at = align(L::kHeaderBytes + sections_.size() * L::kSectionBytes);
        std::vector<std::uint64_t> offsets;
        for (const Section& s : sections_) {
            offsets.push_back(at);
            at = align(at + s.bytes.size());
        }
        std::vector<unsigned char> out(at, 0);
        const auto put = [&](std::size_t pos, auto v) { std::memcpy(out.data() + pos, &v, sizeof v); };
        for (std::size_t i = 0; i < sections_.size(); ++i) {
            const Section& s = sections_[i];
            const std::size_t e = L::kHeaderBytes + i * L::kSectionBytes;
            put(e, s.tag);
            put(e + 4, static_cast<std::uint32_t>(s.dtype));
            put(e + 8, offsets[i]);
            put(e + 16, s.count);
            put(e + 24, s.object);
            if (!s.bytes.empty()) std::memcpy(out.data() + offsets[i], s.bytes.data(), s.bytes.size());
        }
        std::memcpy(out.data(), L::kMagic, 8);
        const bool warped_theta_h =
            std::any_of(sections_.begin(), sections_.end(), [](const Section& s) { return s.tag == L::kThetaHWarp; });
        put(8, std::uint32_t{warped_theta_h ? 2u : 1u});
        put(12, L::kHeaderBytes);
        put(16, static_cast<std::uint64_t>(out.size()));
        put(24, static_cast<std::uint32_t>(sections_.size()));
        put(32, static_cast<std::uint32_t>(root));
        put(36, objects_);
        put(28, runtime::crc32c(out.data() + L::kHeaderBytes, out.size() - L::kHeaderBytes));
        return out;
    }

private:
    std::vector<Section> sections_;
    std::uint32_t objects_ = 1;
};

std::int32_t phi_d_axis(const GridSpec& g) {
    return g.full_circle() ? L::kPhiDNone : g.bilateral() ? L::kPhiDBilateral : L::kPhiDReciprocal;
}

void add_grid(Builder& b, std::uint32_t object, const GridSpec& g, Lookup lookup) {
    b.add_int(L::kGrid, object,
              {g.n_theta_h, g.n_theta_d, g.n_phi_d, g.position == BinPosition::Centre ? 1 : 0, phi_d_axis(g),
               lookup == Lookup::Nearest ? L::kLookupNearest : L::kLookupLinear});
    b.add(L::kWarp, object, L::DType::F64, &g.theta_d_warp, 1);
    if (g.theta_h_warp != 0.0) b.add(L::kThetaHWarp, object, L::DType::F64, &g.theta_h_warp, 1);
}

void add_sampler(Builder& b, const CompactSampler& s) {
    const CompactSampler::Tables& t = s.tables();
    b.add_int(L::kSamplerShape, 0, {t.slices, t.rows, t.cols});
    const double params[2] = {t.cos_theta_max, t.cosine_share};
    b.add(L::kSamplerParams, 0, L::DType::F64, params, 2);
    b.add(L::kSamplerEdges, 0, L::DType::F32, t.s_edges.data(), t.s_edges.size());
    b.add(L::kSamplerRows, 0, L::DType::U32, t.row_cdf.data(), t.row_cdf.size());
    b.add(L::kSamplerCols, 0, L::DType::U16, t.col_cdf.data(), t.col_cdf.size());
    b.add(L::kSamplerWeights, 0, L::DType::F16, t.edge_weight.data(), t.edge_weight.size());
}

// The compact sampler a gridded material carries, or one built from it.
void add_sampler(Builder& b, const Brdf& brdf, const GridSampler& own, const CompactSamplerOptions& options = {}) {
    if (const CompactSampler* c = own.compact()) return add_sampler(b, *c);
    add_sampler(b, CompactSampler(brdf, options));
}

std::vector<std::uint16_t> half_bits(const std::vector<float>& values) {
    std::vector<std::uint16_t> out(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) out[i] = half_from_float(values[i]);  // exact: f16 values
    return out;
}

// A table or a factorisation as object `object`; false for any other kind.
bool add_gridded(Builder& b, std::uint32_t object, const Brdf& brdf) {
    if (const auto* p = dynamic_cast<const PcaBrdf*>(&brdf)) return add_gridded(b, object, p->table());
    if (const auto* t = dynamic_cast<const TabularBrdf*>(&brdf)) {
        b.add_int(L::kKind, object, {static_cast<std::int32_t>(L::Kind::Table)});
        add_grid(b, object, t->table().grid(), t->lookup());
        b.add(L::kValuesF32, object, L::DType::F32, t->table().data(), 3 * t->table().bins());
        return true;
    }
    if (const auto* c = dynamic_cast<const CompactTableBrdf*>(&brdf)) {
        const CompactTable& t = c->table();
        b.add_int(L::kKind, object, {static_cast<std::int32_t>(L::Kind::Table)});
        add_grid(b, object, t.grid(), c->lookup());
        if (t.dtype() == TableDtype::F16) {
            b.add(L::kValuesF16, object, L::DType::F16, t.codes().data(), t.codes().size() / 2);
            b.add(L::kHalfScale, object, L::DType::F32, t.half_scales().data(), 3);
        } else {
            b.add(L::kValuesU8, object, L::DType::U8, t.codes().data(), t.codes().size());
            b.add(L::kLut, object, L::DType::F32, t.lut()[0].data(), 3 * 256);
        }
        return true;
    }
    if (const auto* f = dynamic_cast<const FactoredBrdf*>(&brdf)) {
        const Factors& x = f->factors();
        b.add_int(L::kKind, object, {static_cast<std::int32_t>(L::Kind::Factored)});
        add_grid(b, object, x.grid, Lookup::Linear);
        const std::int32_t space = x.space == FactorSpace::Log    ? L::kSpaceLog
                                   : x.space == FactorSpace::Cbrt ? L::kSpaceCbrt
                                   : x.space == FactorSpace::Cos  ? L::kSpaceCos
                                                                  : L::kSpaceLinear;
        b.add_int(L::kFactorParams, object,
                  {x.layout == FactorLayout::HxDP ? L::kLayoutHxDP : L::kLayoutHDxP, space,
                   x.colour == FactorColour::Shared ? L::kColourShared : L::kColourSeparate, x.rank});
        b.add(L::kFactorMax, object, L::DType::F32, x.max_value.data(), 3);
        if (x.dtype == FactorDtype::F16) {
            const std::vector<std::uint16_t> u = half_bits(x.u), v = half_bits(x.v);
            b.add(L::kFactorU, object, L::DType::F16, u.data(), u.size());
            b.add(L::kFactorV, object, L::DType::F16, v.data(), v.size());
        } else {
            b.add(L::kFactorU, object, L::DType::F32, x.u.data(), x.u.size());
            b.add(L::kFactorV, object, L::DType::F32, x.v.data(), x.v.size());
        }
        if (x.colour == FactorColour::Shared)
            b.add(L::kFactorColour, object, L::DType::F32, x.colour_weights.data(), x.colour_weights.size());
        return true;
    }
    return false;
}

const GridSampler& own_sampler(const Brdf& brdf) {
    if (const auto* p = dynamic_cast<const PcaBrdf*>(&brdf)) return p->table().sampler();
    if (const auto* t = dynamic_cast<const LookupTableBrdf*>(&brdf)) return t->sampler();
    return dynamic_cast<const FactoredBrdf&>(brdf).sampler();
}

}  // namespace

std::vector<unsigned char> encode(const Brdf& brdf, const std::string& describe) {
    // A layout read back is written as it was.
    if (const auto* read = dynamic_cast<const formats::RuntimeBrdf*>(&brdf)) {
        const auto* bytes = static_cast<const unsigned char*>(read->material().data());
        return std::vector<unsigned char>(bytes, bytes + read->material().nbytes());
    }
    Builder b;
    const std::string text = describe.empty() ? brdf.describe() : describe;
    b.add(L::kDesc, 0, L::DType::U8, text.data(), text.size());
    if (const auto* a = dynamic_cast<const AnalyticBrdf*>(&brdf)) {
        b.add_int(L::kKind, 0, {static_cast<std::int32_t>(L::Kind::Analytic)});
        // The families term by term ("lafortune3" as three "lafortune"), so that a reader needs no
        // model-string grammar: parameters follow in the terms' order.
        std::string terms;
        for (const Model::Term& t : a->model().terms()) {
            if (!terms.empty()) terms += '+';
            terms += t.type->name;
        }
        b.add(L::kModel, 0, L::DType::U8, terms.data(), terms.size());
        b.add(L::kParams, 0, L::DType::F64, a->params().data(), a->params().size());
        if (const CompactSampler* c = a->compact_sampler()) {
            add_sampler(b, *c);
        } else {
            const std::vector<double>& albedo = a->sampler().albedo_table();
            b.add(L::kAlbedo, 0, L::DType::F64, albedo.data(), albedo.size());
        }
        return b.finish(L::Kind::Analytic);
    }
    if (const auto* stack = dynamic_cast<const PhiHBrdf*>(&brdf)) {
        const std::int32_t n = static_cast<std::int32_t>(stack->slices().size());
        const std::int32_t symmetry = stack->symmetry() == PhiHSymmetry::None         ? 0
                                      : stack->symmetry() == PhiHSymmetry::Reciprocal ? 1
                                                                                       : 2;
        b.add_int(L::kKind, 0, {static_cast<std::int32_t>(L::Kind::PhiH)});
        b.add_int(L::kPhiH, 0, {symmetry, n});
        for (std::int32_t k = 0; k < n; ++k)
            if (!add_gridded(b, static_cast<std::uint32_t>(k + 1), *stack->slices()[k]))
                throw ValueError("runtime layout: a φh slice of " + stack->slices()[k]->describe() +
                                 " is neither a table nor a factorisation");
        b.set_objects(static_cast<std::uint32_t>(n + 1));
        CompactSamplerOptions options;
        options.view_azimuths = PhiHBrdf::kSamplerAzimuths;
        add_sampler(b, brdf, stack->sampler(), options);
        return b.finish(L::Kind::PhiH);
    }
    if (add_gridded(b, 0, brdf)) {
        add_sampler(b, brdf, own_sampler(brdf));
        const auto* f = dynamic_cast<const FactoredBrdf*>(&brdf);
        return b.finish(f ? L::Kind::Factored : L::Kind::Table);
    }
    // Neither stored as it is: a table of it on MERL's grid. A source that is not reciprocal (real RGL
    // files) keeps φd whole, as the default candidates do: folded, the table would store the mean of
    // f(wi, wo) and f(wo, wi) (13 % off an RGL car paint over directions, against 0.75 % whole).
    TabulateOptions tab;
    tab.grid = GridSpec{90, 90, 180};
    if (!is_reciprocal(brdf)) tab.grid.symmetry = Symmetry::Bilateral;
    const TabularBrdf table(tabulate(brdf, tab).table);
    return encode(table, text + ", tabulated on 90x90x180" +
                             (tab.grid.symmetry == Symmetry::Bilateral ? ", symmetry bilateral" : ""));
}

void write(const std::string& path, const Brdf& brdf, const std::string& describe) {
    const std::vector<unsigned char> bytes = encode(brdf, describe);
    detail::AtomicFile file(path);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

}  // namespace brdfz::runtime_layout
