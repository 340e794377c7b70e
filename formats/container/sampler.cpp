#include "container/sampler.h"

#include "brdfz/errors.h"

namespace brdfz::container::detail {

void write_sampler(h5::WriteNode& rep, SamplerKind kind, const CompactSampler* c) {
    h5::WriteNode g = rep.group("sampler");
    g.attr("kind", std::string(sampler_kind_name(kind)));
    if (kind != SamplerKind::Compact) return;
    const CompactSampler::Tables& t = c->tables();
    const auto n = [](int x) { return static_cast<std::uint64_t>(x); };
    g.attr("slices", n(t.slices));
    g.attr("rows", n(t.rows));
    g.attr("cols", n(t.cols));
    g.attr("cos_theta_max", t.cos_theta_max);
    g.attr("cosine_share", t.cosine_share);
    g.dataset("s_edges", h5::DType::F32, {n(t.rows) + 1}, t.s_edges.data());
    g.dataset("row_cdf", h5::DType::U32, {n(t.slices), n(t.rows)}, t.row_cdf.data());
    g.dataset("col_cdf", h5::DType::U16, {n(t.slices), n(t.rows), n(t.cols)}, t.col_cdf.data());
    g.dataset("edge_weight", h5::DType::F16, {n(t.slices), n(t.rows) + 1}, t.edge_weight.data());
}

StoredSampler read_sampler(const h5::ReadNode& rep) {
    if (!rep.has("sampler")) return {};
    const h5::ReadNode g = rep.group("sampler");
    const auto bad = [&](const std::string& what) { throw FormatError(g.file(), g.path() + ": " + what); };
    const std::string kind = g.str("kind");
    if (kind == "fine") return {SamplerKind::Fine, std::nullopt};
    if (kind == "none") return {SamplerKind::None, std::nullopt};
    if (kind != "compact") bad("unknown sampler kind '" + kind + "'");
    CompactSampler::Tables t;
    const auto count = [&](const char* name, std::uint64_t max) {
        const std::uint64_t v = g.u64(name);
        if (v < 1 || v > max) bad("attribute '" + std::string(name) + "' is " + std::to_string(v) + ", not in 1.." + std::to_string(max));
        return static_cast<int>(v);
    };
    t.slices = count("slices", 1024);
    t.rows = count("rows", 4096);
    t.cols = count("cols", 4096);
    t.cos_theta_max = g.f64("cos_theta_max");
    t.cosine_share = g.f64("cosine_share");
    const auto n = [](int x) { return static_cast<std::uint64_t>(x); };
    // Shapes checked before anything is allocated (and by the reader, sizes against the file).
    const auto load = [&](const char* name, h5::DType type, const std::vector<std::uint64_t>& shape, auto& out) {
        const h5::Dataset d = g.dataset(name);
        if (d.type() != type || d.shape() != shape)
            bad(std::string("dataset '") + name + "' is not a " + h5::dtype_name(type) + " array of the sampler's shape");
        out.resize(d.count());
        d.read(out.data());
    };
    load("s_edges", h5::DType::F32, {n(t.rows) + 1}, t.s_edges);
    load("row_cdf", h5::DType::U32, {n(t.slices), n(t.rows)}, t.row_cdf);
    load("col_cdf", h5::DType::U16, {n(t.slices), n(t.rows), n(t.cols)}, t.col_cdf);
    load("edge_weight", h5::DType::F16, {n(t.slices), n(t.rows) + 1}, t.edge_weight);
    try {
        return {SamplerKind::Compact, CompactSampler(std::move(t))};
    } catch (const ValueError& e) {
        bad(e.what());
        throw;  // unreachable: bad() throws
    }
}

}  // namespace brdfz::container::detail
