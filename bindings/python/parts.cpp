// Brdf.parts() and Brdf.sampler_parts(): a representation's stored arrays and parameters, and its
// sampler's tables, read-only, for code that re-implements evaluation and sampling elsewhere (the
// Mitsuba bridge's Dr.Jit port, brdfz/_native). Large arrays are views that keep the Brdf alive;
// small ones are copies. None for kinds without parts (RGL files, scattered measurements).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/sample/grid_sampler.h"
#include "brdfz/sample/lobes.h"
#include "module.h"

namespace brdfz::python {
namespace {

// A read-only 1-D or 2-D view of n (× cols) elements at p, owned by `owner`.
template <typename T>
py::array view(const T* p, py::ssize_t n, py::ssize_t cols, const py::object& owner) {
    py::array_t<T> a = cols > 0 ? py::array_t<T>({n, cols}, {cols * static_cast<py::ssize_t>(sizeof(T)),
                                                              static_cast<py::ssize_t>(sizeof(T))},
                                                 p, owner)
                                : py::array_t<T>({n}, {static_cast<py::ssize_t>(sizeof(T))}, p, owner);
    a.attr("setflags")(py::arg("write") = false);
    return a;
}

template <typename T>
py::array copy(const T* p, std::size_t n) {
    py::array_t<T> a(static_cast<py::ssize_t>(n));
    std::copy_n(p, n, a.mutable_data());
    return a;
}

py::dict grid_dict(const GridSpec& g) {
    py::dict d;
    d["n_theta_h"] = g.n_theta_h;
    d["n_theta_d"] = g.n_theta_d;
    d["n_phi_d"] = g.n_phi_d;
    d["position"] = g.position == BinPosition::Centre ? "centre" : "start";
    d["theta_d_warp"] = g.theta_d_warp;
    d["theta_h_warp"] = g.theta_h_warp;
    d["symmetry"] = symmetry_name(g.symmetry);
    return d;
}

py::dict halfvector_parts(const HalfVectorSampler& s) {
    const Piecewise2D::View v = s.slices();
    const std::size_t K = s.theta_o().size(), R = static_cast<std::size_t>(v.rows), C = static_cast<std::size_t>(v.cols);
    py::dict d;
    d["kind"] = "halfvector";
    d["share"] = s.options().cosine_share;
    d["theta_o"] = copy(s.theta_o().data(), K);
    d["rows"] = v.rows;
    d["cols"] = v.cols;
    d["marginal"] = copy(v.marginal, K * (R + 1));
    d["conditional"] = copy(v.conditional, K * R * (C + 1));
    d["density"] = copy(v.density, K * R * C);
    d["marginal_guide"] = copy(v.marginal_guide, K * R);
    d["conditional_guide"] = copy(v.conditional_guide, K * R * C);
    return d;
}

}  // namespace

std::optional<py::dict> brdf_parts(const BrdfPtr& brdf) {
    const py::object owner = py::cast(brdf);
    py::dict d;
    if (const auto* t = dynamic_cast<const TabularBrdf*>(brdf.get())) {
        d["kind"] = "tabular";
        d["grid"] = grid_dict(t->table().grid());
        d["lookup"] = lookup_name(t->lookup());
        d["values"] = view(t->table().data(), static_cast<py::ssize_t>(3 * t->table().bins()), 0, owner);
    } else if (const auto* c = dynamic_cast<const CompactTableBrdf*>(brdf.get())) {
        const CompactTable& ct = c->table();
        d["kind"] = "compact";
        d["grid"] = grid_dict(ct.grid());
        d["lookup"] = lookup_name(c->lookup());
        d["dtype"] = table_dtype_name(ct.dtype());
        d["codes"] = view(ct.codes().data(), static_cast<py::ssize_t>(ct.codes().size()), 0, owner);
        d["half_scales"] = copy(ct.half_scales().data(), 3);
        py::array_t<float> lut({3, 256});
        for (int ch = 0; ch < 3; ++ch) std::copy_n(ct.lut()[ch].data(), 256, lut.mutable_data() + 256 * ch);
        d["lut"] = lut;
    } else if (const auto* f = dynamic_cast<const FactoredBrdf*>(brdf.get())) {
        const Factors& x = f->factors();
        const py::ssize_t m = x.row_width();
        d["kind"] = "factored";
        d["grid"] = grid_dict(x.grid);
        d["method"] = factor_method_name(x.method);
        d["space"] = factor_space_name(x.space);
        d["layout"] = factor_layout_name(x.layout);
        d["colour"] = factor_colour_name(x.colour);
        d["dtype"] = factor_dtype_name(x.dtype);
        d["rank"] = x.rank;
        d["u"] = view(x.u.data(), x.rows(), m, owner);
        d["v"] = view(x.v.data(), x.columns(), m, owner);
        d["colour_weights"] = x.colour == FactorColour::Shared
                                  ? view(x.colour_weights.data(), 3, x.rank, owner)
                                  : py::array(py::array_t<float>(std::vector<py::ssize_t>{0, x.rank}));
        d["max_value"] = copy(x.max_value.data(), 3);
    } else if (const auto* p = dynamic_cast<const PcaBrdf*>(brdf.get())) {
        const PcaBasis& b = p->basis();
        const py::ssize_t dims = static_cast<py::ssize_t>(b.dims());
        d["kind"] = "pca";
        d["grid"] = grid_dict(b.grid());
        d["lookup"] = lookup_name(p->table().lookup());
        d["epsilon"] = b.epsilon();
        d["coefficients"] = copy(p->coefficients().data(), p->coefficients().size());
        d["median"] = view(b.median().data(), dims, 0, owner);
        d["mean"] = view(b.mean().data(), dims, 0, owner);
        d["components"] = view(b.components().data(), b.k_max(), dims, owner);
        d["weights"] = view(b.weights().data(), static_cast<py::ssize_t>(b.weights().size()), 0, owner);
    } else if (const auto* a = dynamic_cast<const AnalyticBrdf*>(brdf.get())) {
        d["kind"] = "analytic";
        d["model"] = a->model().text();
        py::list terms;
        for (const Model::Term& t : a->model().terms())
            terms.append(py::make_tuple(std::string(t.type->name), t.offset, t.label));
        d["terms"] = terms;
        d["params"] = copy(a->params().data(), a->params().size());
    } else {
        return std::nullopt;
    }
    return d;
}

namespace {

py::dict compact_parts(const CompactSampler& s) {
    const CompactSampler::Tables& t = s.tables();
    py::dict d;
    d["kind"] = "compact";
    d["slices"] = t.slices;
    d["rows"] = t.rows;
    d["cols"] = t.cols;
    d["cos_theta_max"] = t.cos_theta_max;
    d["share"] = t.cosine_share;
    d["s_edges"] = copy(t.s_edges.data(), t.s_edges.size());
    d["row_cdf"] = copy(t.row_cdf.data(), t.row_cdf.size());
    d["col_cdf"] = copy(t.col_cdf.data(), t.col_cdf.size());
    d["edge_weight"] = copy(t.edge_weight.data(), t.edge_weight.size());  // binary16 bits
    return d;
}

std::optional<py::dict> grid_sampler_parts(const GridSampler& s) {
    if (const CompactSampler* c = s.compact()) return compact_parts(*c);
    if (const HalfVectorSampler* f = s.fine()) return halfvector_parts(*f);
    return std::nullopt;
}

}  // namespace

std::optional<py::dict> sampler_parts(const BrdfPtr& brdf) {
    if (const auto* t = dynamic_cast<const LookupTableBrdf*>(brdf.get())) return grid_sampler_parts(t->sampler());
    if (const auto* f = dynamic_cast<const FactoredBrdf*>(brdf.get())) return grid_sampler_parts(f->sampler());
    if (const auto* p = dynamic_cast<const PcaBrdf*>(brdf.get())) return grid_sampler_parts(p->table().sampler());
    if (const auto* h = dynamic_cast<const PhiHBrdf*>(brdf.get())) return grid_sampler_parts(h->sampler());
    if (const auto* a = dynamic_cast<const AnalyticBrdf*>(brdf.get())) {
        if (const CompactSampler* c = a->compact_sampler()) return compact_parts(*c);
        const std::vector<double>& albedo = a->sampler().albedo_table();
        const py::ssize_t terms = static_cast<py::ssize_t>(a->model().terms().size());
        py::array_t<double> table({static_cast<py::ssize_t>(LobeMixture::kAlbedoNodes), terms});
        std::copy(albedo.begin(), albedo.end(), table.mutable_data());
        py::dict d;
        d["kind"] = "lobes";
        d["albedo"] = table;
        return d;
    }
    return std::nullopt;
}

}  // namespace brdfz::python
