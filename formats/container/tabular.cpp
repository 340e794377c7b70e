// Tabular storage: a Rusinkiewicz table (any resolution) as one dataset "values" of shape
// [nθh, nθd, nφd, 3] in MERL's bin order with RGB interleaved, exactly Table's memory layout, so
// reading is a single read into the table. Invalid entries are stored as the table holds them (NaN).
// Element types: float32 now; float16 and 8-bit quantised tables will be further features
// ("tabular.float16", "tabular.uint8" with per-channel scale and offset attributes; formats/SPEC.md).
#include "brdfz/errors.h"
#include "storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kTabular{"tabular", 1};
const Feature kFloat32{"tabular.float32", 1};

const char* position_name(BinPosition p) { return p == BinPosition::Centre ? "centre" : "start"; }

std::vector<Feature> needs(const Brdf& brdf) {
    if (!dynamic_cast<const TabularBrdf*>(&brdf)) return {};
    return {kTabular, kFloat32};
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const Table& t = dynamic_cast<const TabularBrdf&>(brdf).table();
    const GridSpec& g = t.grid();
    const std::uint64_t dims[3] = {static_cast<std::uint64_t>(g.n_theta_h), static_cast<std::uint64_t>(g.n_theta_d),
                                   static_cast<std::uint64_t>(g.n_phi_d)};
    rep.attr("grid", std::span<const std::uint64_t>(dims));
    rep.attr("bin_position", std::string(position_name(g.position)));
    rep.attr("theta_h_axis", std::string("sqrt"));
    rep.attr("dtype", std::string("float32"));
    rep.attr("invalid", std::string("nan"));
    rep.dataset("values", h5::DType::F32, {dims[0], dims[1], dims[2], 3}, t.data());
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext& ctx) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::string dtype = rep.str("dtype");
    if (dtype != "float32") bad("unsupported table element type '" + dtype + "'");
    const std::vector<std::uint64_t> dims = rep.u64s("grid");
    if (dims.size() != 3) bad("attribute 'grid' has " + std::to_string(dims.size()) + " entries, expected 3");
    for (std::uint64_t d : dims)
        if (d < 1 || d > static_cast<std::uint64_t>(GridSpec::kMaxAxis))
            bad("grid axis " + std::to_string(d) + " outside 1.." + std::to_string(GridSpec::kMaxAxis));
    const std::string position = rep.str("bin_position");
    if (position != "centre" && position != "start") bad("unknown bin_position '" + position + "'");
    const std::string axis = rep.str("theta_h_axis");
    if (axis != "sqrt") bad("unknown theta_h_axis '" + axis + "'");

    const GridSpec grid{static_cast<int>(dims[0]), static_cast<int>(dims[1]), static_cast<int>(dims[2]),
                        position == "centre" ? BinPosition::Centre : BinPosition::Start};
    const h5::Dataset values = rep.dataset("values");
    const std::vector<std::uint64_t> expected{dims[0], dims[1], dims[2], 3};
    if (values.type() != h5::DType::F32 || values.shape() != expected)
        bad("dataset 'values' is not a float32 array of shape " + grid.str() + "x3");
    // Shape checked against the grid, and its size against the file, before the table is allocated;
    // every entry is then read.
    Table table(grid, Table::Uninitialized{});
    values.read(table.data());
    return std::make_unique<TabularBrdf>(std::move(table), ctx.lookup);
}

}  // namespace

const StorageModule& tabular_storage() {
    static const StorageModule m{"tabular", {kTabular, kFloat32}, &needs, &write, &read};
    return m;
}

}  // namespace brdfz::container::detail
