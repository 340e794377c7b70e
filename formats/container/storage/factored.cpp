// Factored storage: a FactoredBrdf's factors as datasets "u" [rows, m] and "v" [columns, m], float32
// or float16 (Factors::dtype; FactoredBrdf keeps float16 factors as the floats they are, so writing
// them as float16 is exact), and "colour" [3, rank] float32 for shared colour, with the grid, layout,
// transform space, method and colour mode as attributes (formats/SPEC.md). Factors round-trip bit for
// bit, so evaluation does too.
#include <Eigen/Core>

#include "brdfz/errors.h"
#include "brdfz/repr/factored.h"
#include "container/sampler.h"
#include "container/storage.h"

namespace brdfz::container::detail {
namespace {

const Feature kFactored{"factored", 2};
const Feature kWarpedThetaD{"factored.warped-theta-d", 2};
const Feature kWarpedThetaH{"factored.warped-theta-h", 7};
// Readers without it refuse float16 factors by this name rather than misreading them.
const Feature kFloat16{"factored.float16", 2};
const Feature kFullPhiD{"factored.full-phi-d", 3};
const Feature kBilateralPhiD{"factored.bilateral-phi-d", 5};

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* f = dynamic_cast<const FactoredBrdf*>(&brdf);
    if (!f) return {};
    // As for tables: only a warped grid needs the feature, so linear-axis factors stay readable without it.
    std::vector<Feature> out{kFactored};
    if (f->factors().grid.theta_d_warp != 0.0) out.push_back(kWarpedThetaD);
    if (f->factors().grid.theta_h_warp != 0.0) out.push_back(kWarpedThetaH);
    if (f->factors().dtype == FactorDtype::F16) out.push_back(kFloat16);
    if (f->factors().grid.full_circle()) out.push_back(kFullPhiD);
    if (f->factors().grid.bilateral()) out.push_back(kBilateralPhiD);
    return out;
}

std::vector<std::uint16_t> to_half_bits(const std::vector<float>& values) {
    std::vector<std::uint16_t> bits(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) bits[i] = Eigen::numext::bit_cast<std::uint16_t>(Eigen::half(values[i]));
    return bits;
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const auto& factored = dynamic_cast<const FactoredBrdf&>(brdf);
    const Factors& f = factored.factors();
    const GridSpec& g = f.grid;
    const std::uint64_t dims[3] = {static_cast<std::uint64_t>(g.n_theta_h), static_cast<std::uint64_t>(g.n_theta_d),
                                   static_cast<std::uint64_t>(g.n_phi_d)};
    rep.attr("grid", std::span<const std::uint64_t>(dims));
    rep.attr("bin_position", std::string(g.position == BinPosition::Centre ? "centre" : "start"));
    write_theta_h_axis(rep, g);
    write_theta_d_axis(rep, g);
    write_phi_d_axis(rep, g);
    rep.attr("method", std::string(factor_method_name(f.method)));
    rep.attr("space", std::string(factor_space_name(f.space)));
    rep.attr("layout", std::string(factor_layout_name(f.layout)));
    rep.attr("colour", std::string(factor_colour_name(f.colour)));
    rep.attr("rank", static_cast<std::uint64_t>(f.rank));
    const bool half = f.dtype == FactorDtype::F16;
    rep.attr("dtype", std::string(half ? "float16" : "float32"));
    const double top[3] = {f.max_value[0], f.max_value[1], f.max_value[2]};
    rep.attr("max_value", std::span<const double>(top));
    const std::uint64_t m = static_cast<std::uint64_t>(f.row_width());
    const std::vector<std::uint64_t> u_shape{static_cast<std::uint64_t>(f.rows()), m},
        v_shape{static_cast<std::uint64_t>(f.columns()), m};
    if (half) {
        rep.dataset("u", h5::DType::F16, u_shape, to_half_bits(f.u).data());
        rep.dataset("v", h5::DType::F16, v_shape, to_half_bits(f.v).data());
    } else {
        rep.dataset("u", h5::DType::F32, u_shape, f.u.data());
        rep.dataset("v", h5::DType::F32, v_shape, f.v.data());
    }
    if (f.colour == FactorColour::Shared)
        rep.dataset("colour", h5::DType::F32, {3, static_cast<std::uint64_t>(f.rank)}, f.colour_weights.data());
    write_sampler(rep, factored.sampler());
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext&) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    // The attributes are checksummed, so an unknown name is from a newer writer, not damage; either
    // way it is refused with the value named.
    const auto choice = [&](const char* name, auto parse_fn) {
        const std::string text = rep.str(name);
        try {
            return parse_fn(text);
        } catch (const ValueError& e) {
            bad(e.what());
            throw;  // unreachable: bad() throws
        }
    };
    Factors f;
    f.method = choice("method", parse_factor_method);
    f.space = choice("space", parse_factor_space);
    f.layout = choice("layout", parse_factor_layout);
    f.colour = choice("colour", parse_factor_colour);
    const std::string dtype = rep.str("dtype");
    if (dtype != "float32" && dtype != "float16") bad("unsupported factor element type '" + dtype + "'");
    f.dtype = dtype == "float16" ? FactorDtype::F16 : FactorDtype::F32;
    f.grid = read_grid(rep, true);
    const std::uint64_t rows = static_cast<std::uint64_t>(f.rows()), cols = static_cast<std::uint64_t>(f.columns());
    const std::uint64_t rank = rep.u64("rank");
    if (rank < 1 || rank > std::min(rows, cols))
        bad("rank " + std::to_string(rank) + " outside 1.." + std::to_string(std::min(rows, cols)));
    f.rank = static_cast<int>(rank);
    // Optional: files written before it have no ceiling but the float range.
    if (rep.has_attr("max_value")) {
        const std::vector<double> top = rep.f64s("max_value");
        if (top.size() != 3) bad("attribute 'max_value' has " + std::to_string(top.size()) + " entries, expected 3");
        for (int c = 0; c < 3; ++c) f.max_value[c] = static_cast<float>(top[c]);
    }
    const std::uint64_t m = static_cast<std::uint64_t>(f.row_width());

    // Shapes checked against the attributes (and by the reader, sizes against the file) before allocating.
    const auto load = [&](const char* name, std::uint64_t n, std::uint64_t width, bool half, std::vector<float>& out) {
        const h5::Dataset d = rep.dataset(name);
        if (d.type() != (half ? h5::DType::F16 : h5::DType::F32) || d.shape() != std::vector<std::uint64_t>{n, width})
            bad(std::string("dataset '") + name + "' is not a " + (half ? "float16" : "float32") + " array of shape " +
                std::to_string(n) + "x" + std::to_string(width));
        out.resize(n * width);
        if (!half) return d.read(out.data());
        std::vector<std::uint16_t> bits(n * width);
        d.read(bits.data());
        for (std::size_t i = 0; i < bits.size(); ++i) out[i] = static_cast<float>(Eigen::numext::bit_cast<Eigen::half>(bits[i]));
    };
    const bool half = f.dtype == FactorDtype::F16;
    load("u", rows, m, half, f.u);
    load("v", cols, m, half, f.v);
    if (f.colour == FactorColour::Shared) load("colour", 3, rank, false, f.colour_weights);
    try {
        return with_sampler(rep, [&](auto sampler) { return std::make_unique<FactoredBrdf>(std::move(f), std::move(sampler)); });
    } catch (const ValueError& e) {
        bad(e.what());
        throw;  // unreachable
    }
}

void source_info(const Brdf& brdf, SourceInfo& info) {
    const Factors& f = dynamic_cast<const FactoredBrdf&>(brdf).factors();
    info.dims = {static_cast<std::size_t>(f.grid.n_theta_h), static_cast<std::size_t>(f.grid.n_theta_d),
                 static_cast<std::size_t>(f.grid.n_phi_d)};
    info.dims_of = "grid of the rank-" + std::to_string(f.rank) + " " + factor_method_name(f.method) + " factors";
    info.counts = {};
    info.counts.valid = f.grid.bins();  // the factors give every bin a value
    info.has_range = false;
    info.min_value = info.max_value = 0.0;
}

}  // namespace

void register_factored(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"factored", {kFactored, kWarpedThetaD, kWarpedThetaH, kFloat16, kFullPhiD, kBilateralPhiD}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace brdfz::container::detail
