// Tabular storage: a Rusinkiewicz table (any resolution; one φd bin for a bivariate table) as one
// dataset "values" of shape [nθh, nθd, nφd, 3] in MERL's bin order with RGB interleaved, exactly the
// memory layout of Table and CompactTable, so reading is a single read into the table. Element types:
// float32 (TabularBrdf; invalid entries NaN as the table holds them), float16 and uint8 log-quantised
// codes (CompactTableBrdf) with their per-channel decoding parameters as attributes (formats/SPEC.md).
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "brdfz/errors.h"
#include "brdfz/repr/compact_table.h"
#include "container/sampler.h"
#include "container/storage.h"
#include "detail/table_io.h"

namespace brdfz::container::detail {
namespace {

const Feature kTabular{"tabular", 1};
const Feature kFloat32{"tabular.float32", 1};
const Feature kFloat16{"tabular.float16", 2};
const Feature kUint8Log{"tabular.uint8-log", 2};
const Feature kWarpedThetaD{"tabular.warped-theta-d", 2};
const Feature kWarpedThetaH{"tabular.warped-theta-h", 7};
const Feature kFullPhiD{"tabular.full-phi-d", 3};
const Feature kBilateralPhiD{"tabular.bilateral-phi-d", 5};

const char* position_name(BinPosition p) { return p == BinPosition::Centre ? "centre" : "start"; }

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* t = dynamic_cast<const TabularBrdf*>(&brdf);
    const auto* c = dynamic_cast<const CompactTableBrdf*>(&brdf);
    if (!t && !c) return {};
    std::vector<Feature> out{kTabular, t ? kFloat32 : c->table().dtype() == TableDtype::F16 ? kFloat16 : kUint8Log};
    // Only a warped grid needs the feature, so linear tables stay readable by readers without it.
    const GridSpec& g = t ? t->table().grid() : c->table().grid();
    if (g.theta_d_warp != 0.0) out.push_back(kWarpedThetaD);
    if (g.theta_h_warp != 0.0) out.push_back(kWarpedThetaH);
    // Likewise φd over [0, 2π) or folded by the mirror: a reader without the feature refuses the table
    // instead of reading its φd axis as the reciprocal one.
    if (g.full_circle()) out.push_back(kFullPhiD);
    if (g.bilateral()) out.push_back(kBilateralPhiD);
    return out;
}

void write_grid(h5::WriteNode& rep, const GridSpec& g) {
    const std::uint64_t dims[3] = {static_cast<std::uint64_t>(g.n_theta_h), static_cast<std::uint64_t>(g.n_theta_d),
                                   static_cast<std::uint64_t>(g.n_phi_d)};
    rep.attr("grid", std::span<const std::uint64_t>(dims));
    rep.attr("bin_position", std::string(position_name(g.position)));
    write_theta_h_axis(rep, g);
    write_theta_d_axis(rep, g);
    write_phi_d_axis(rep, g);
}

std::vector<std::uint64_t> values_shape(const GridSpec& g) {
    return {static_cast<std::uint64_t>(g.n_theta_h), static_cast<std::uint64_t>(g.n_theta_d),
            static_cast<std::uint64_t>(g.n_phi_d), 3};
}

void write_codec(h5::WriteNode& rep, const char* name, const CompactTable& t, double ChannelCodec::*field) {
    const double v[3] = {t.codecs()[0].*field, t.codecs()[1].*field, t.codecs()[2].*field};
    rep.attr(name, std::span<const double>(v));
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    if (const auto* c = dynamic_cast<const CompactTableBrdf*>(&brdf)) {
        const CompactTable& t = c->table();
        write_grid(rep, t.grid());
        if (t.dtype() == TableDtype::F16) {
            rep.attr("dtype", std::string("float16"));
            rep.attr("invalid", std::string("nan"));
            write_codec(rep, "scale", t, &ChannelCodec::scale);
            rep.dataset("values", h5::DType::F16, values_shape(t.grid()), t.codes().data());
        } else {
            rep.attr("dtype", std::string("uint8"));
            rep.attr("transform", std::string("log1p"));
            rep.attr("invalid", std::string("255"));
            write_codec(rep, "gain", t, &ChannelCodec::gain);
            write_codec(rep, "offset", t, &ChannelCodec::offset);
            write_codec(rep, "scale", t, &ChannelCodec::scale);
            rep.dataset("values", h5::DType::U8, values_shape(t.grid()), t.codes().data());
        }
        write_sampler(rep, c->sampler());
        return;
    }
    const auto& tabular = dynamic_cast<const TabularBrdf&>(brdf);
    const Table& t = tabular.table();
    write_grid(rep, t.grid());
    rep.attr("dtype", std::string("float32"));
    rep.attr("invalid", std::string("nan"));
    rep.dataset("values", h5::DType::F32, values_shape(t.grid()), t.data());
    write_sampler(rep, tabular.sampler());
}

// One codec field of the three channels.
std::array<double, 3> read_codec(const h5::ReadNode& rep, const char* name) {
    const std::vector<double> v = rep.f64s(name);
    if (v.size() != 3)
        throw FormatError(rep.file(), rep.path() + ": attribute '" + name + "' has " + std::to_string(v.size()) +
                                          " entries, expected 3");
    return {v[0], v[1], v[2]};
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext& ctx) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::string dtype = rep.str("dtype");
    if (dtype != "float32" && dtype != "float16" && dtype != "uint8") bad("unsupported table element type '" + dtype + "'");
    const GridSpec grid = read_grid(rep, true);
    const h5::Dataset values = rep.dataset("values");
    const h5::DType type = dtype == "float32" ? h5::DType::F32 : dtype == "float16" ? h5::DType::F16 : h5::DType::U8;
    if (values.type() != type || values.shape() != values_shape(grid))
        bad("dataset 'values' is not a " + dtype + " array of shape " + grid.str() + "x3");
    // Shape checked against the grid, and its size against the file, before the table is allocated;
    // every entry is then read.
    if (type == h5::DType::F32) {
        Table table(grid, Table::Uninitialized{});
        values.read(table.data());
        // The float16 and uint8 rules (CompactTable): NaN is the invalid marker, and nothing else may
        // be outside [0, FLT_MAX].
        std::size_t inf = 0, negative = 0, nan = 0;
        for (std::size_t k = 0; k < 3 * grid.bins(); ++k) {
            const float v = table.data()[k];
            inf += std::isinf(v);
            nan += std::isnan(v);
            negative += v < 0.0f && !std::isinf(v);
        }
        if (inf || negative)
            bad("dataset 'values' holds " + std::to_string(inf) + " infinite and " + std::to_string(negative) +
                " negative values (of " + std::to_string(3 * grid.bins()) + "); a table holds values >= 0 and NaN "
                "for unmeasured entries");
        if (nan == 3 * grid.bins()) bad("dataset 'values' holds no value (every entry is NaN): nothing to evaluate");
        return with_sampler(rep, [&](auto sampler) {
            return std::make_unique<TabularBrdf>(std::move(table), ctx.lookup, std::move(sampler));
        });
    }
    std::array<ChannelCodec, 3> codecs;
    if (type == h5::DType::F16) {
        const std::array<double, 3> scale = read_codec(rep, "scale");
        for (int ch = 0; ch < 3; ++ch) codecs[ch].scale = scale[ch];
    } else {
        if (rep.str("transform") != "log1p") bad("unknown uint8 transform '" + rep.str("transform") + "'");
        const std::array<double, 3> gain = read_codec(rep, "gain"), offset = read_codec(rep, "offset"),
                                    scale = read_codec(rep, "scale");
        for (int ch = 0; ch < 3; ++ch) codecs[ch] = {gain[ch], offset[ch], scale[ch]};
    }
    std::vector<std::uint8_t> codes(values.nbytes());
    values.read(codes.data());
    std::optional<CompactTable> table;
    try {
        table.emplace(grid, dtype == "float16" ? TableDtype::F16 : TableDtype::U8Log, std::move(codes), codecs);
    } catch (const ValueError& e) {
        bad(e.what());
    }
    bool any = false;
    for (std::size_t k = 0; k < grid.bins() && !any; ++k)
        for (int ch = 0; ch < 3; ++ch) any = any || !std::isnan(table->at(k, ch));
    if (!any) bad("dataset 'values' holds no value (every entry is the invalid code): nothing to evaluate");
    return with_sampler(rep, [&](auto sampler) {
        return std::make_unique<CompactTableBrdf>(std::move(*table), ctx.lookup, std::move(sampler));
    });
}

// A compact table's range is that of its decoded values.
void source_info(const Brdf& brdf, SourceInfo& info) {
    if (const Table* t = brdf.stored_table()) {
        info = brdfz::detail::table_info(info.format, *t, info.counts);
        return;
    }
    const CompactTable& c = dynamic_cast<const CompactTableBrdf&>(brdf).table();
    const GridSpec& g = c.grid();
    info.dims = {static_cast<std::size_t>(g.n_theta_h), static_cast<std::size_t>(g.n_theta_d),
                 static_cast<std::size_t>(g.n_phi_d)};
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t k = 0; k < g.bins(); ++k)
        for (int ch = 0; ch < 3; ++ch) {
            const float v = c.at(k, ch);
            if (std::isnan(v)) continue;
            lo = std::min<double>(lo, v);
            hi = std::max<double>(hi, v);
        }
    info.min_value = lo <= hi ? lo : 0.0;
    info.max_value = lo <= hi ? hi : 0.0;
}

}  // namespace

void write_theta_d_axis(h5::WriteNode& rep, const GridSpec& g) {
    if (g.theta_d_warp == 0.0) return;
    rep.attr("theta_d_axis", std::string("warped"));
    rep.attr("theta_d_warp", g.theta_d_warp);
}

double read_theta_d_warp(const h5::ReadNode& rep) {
    if (!rep.has_attr("theta_d_axis")) return 0.0;  // the linear θd axis
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::string d_axis = rep.str("theta_d_axis");
    if (d_axis != "warped") bad("unknown theta_d_axis '" + d_axis + "'");
    const double warp = rep.f64("theta_d_warp");
    if (!(warp > 0.0 && warp <= GridSpec::kMaxWarp)) bad("theta_d_warp " + std::to_string(warp) + " outside (0, 0.95]");
    return warp;
}

void write_theta_h_axis(h5::WriteNode& rep, const GridSpec& g) {
    rep.attr("theta_h_axis", std::string(g.theta_h_warp == 0.0 ? "sqrt" : "warped"));
    if (g.theta_h_warp != 0.0) rep.attr("theta_h_warp", g.theta_h_warp);
}

double read_theta_h_warp(const h5::ReadNode& rep) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::string h_axis = rep.str("theta_h_axis");
    if (h_axis == "sqrt") return 0.0;
    if (h_axis != "warped") bad("unknown theta_h_axis '" + h_axis + "'");
    const double s = rep.f64("theta_h_warp");
    if (!(s >= GridSpec::kMinThetaHWarp && s <= GridSpec::kMaxThetaHWarp))
        bad("theta_h_warp " + std::to_string(s) + " outside [" + std::to_string(GridSpec::kMinThetaHWarp) + ", " +
            std::to_string(GridSpec::kMaxThetaHWarp) + "] radians");
    return s;
}

void write_phi_d_axis(h5::WriteNode& rep, const GridSpec& g) {
    if (g.full_circle()) rep.attr("phi_d_axis", std::string("full"));
    if (g.bilateral()) rep.attr("phi_d_axis", std::string("bilateral"));
}

GridSpec read_grid(const h5::ReadNode& rep, bool warped_axes) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::vector<std::uint64_t> dims = rep.u64s("grid");
    if (dims.size() != 3) bad("attribute 'grid' has " + std::to_string(dims.size()) + " entries, expected 3");
    for (std::uint64_t d : dims)
        if (d < 1 || d > static_cast<std::uint64_t>(GridSpec::kMaxAxis))
            bad("grid axis " + std::to_string(d) + " outside 1.." + std::to_string(GridSpec::kMaxAxis));
    const std::string position = rep.str("bin_position");
    if (position != "centre" && position != "start") bad("unknown bin_position '" + position + "'");
    const std::string axis = rep.str("theta_h_axis");
    if (!warped_axes && axis != "sqrt") bad("unknown theta_h_axis '" + axis + "'");
    return {static_cast<int>(dims[0]), static_cast<int>(dims[1]), static_cast<int>(dims[2]),
            position == "centre" ? BinPosition::Centre : BinPosition::Start, warped_axes ? read_theta_d_warp(rep) : 0.0,
            read_phi_d_symmetry(rep), warped_axes ? read_theta_h_warp(rep) : 0.0};
}

Symmetry read_phi_d_symmetry(const h5::ReadNode& rep) {
    if (!rep.has_attr("phi_d_axis")) return Symmetry::Reciprocal;
    const std::string axis = rep.str("phi_d_axis");
    if (axis == "full") return Symmetry::None;
    if (axis == "bilateral") return Symmetry::Bilateral;
    throw FormatError(rep.file(), rep.path() + ": unknown phi_d_axis '" + axis + "'");
}

void register_tabular(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"tabular", {kTabular, kFloat32, kFloat16, kUint8Log, kWarpedThetaD, kWarpedThetaH, kFullPhiD,
                                                 kBilateralPhiD},
                                 &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
