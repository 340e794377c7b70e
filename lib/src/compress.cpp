#include "brdfz/compress.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdio>
#include <numbers>
#include <optional>

#include "brdfz/errors.h"
#include "brdfz/fit/fit.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/repr/pca.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/tabulate.h"

namespace brdfz {
namespace {

using Builder = Compressed (*)(const Brdf& source, const ReprSpec& spec, const CompressOptions& options);

// What tabulating `source` left out or changed, for Compressed::notes.
void note_tabulation(const Brdf& source, const Tabulated& t, Compressed& out) {
    if (t.counts.clamped > 0)
        out.notes.push_back(std::to_string(t.counts.clamped) + " negative values clamped to 0 when tabulating");
    if (t.extrapolated > 0) {
        char deg[32];
        std::snprintf(deg, sizeof deg, "%.2f", source.measured_theta_max() * 180.0 / std::numbers::pi);
        out.notes.push_back(std::to_string(t.extrapolated) + " samples beyond the measured elevation (" + deg +
                            " deg) taken at it");
    }
}

// Tabulates `source` on `grid` (box-filtered by `supersample`) and keeps the table in `dtype`.
Compressed build_table(const Brdf& source, const GridSpec& grid, std::array<int, 3> supersample,
                       TabulateOptions::Filter filter, TabulateOptions::FitWeight weight, TableDtype dtype,
                       Lookup lookup, const CompressOptions& options) {
    TabulateOptions tab;
    tab.grid = grid;
    tab.grid.validate();
    tab.supersample = supersample;
    tab.filter = filter;
    tab.fit_weight = weight;
    tab.threads = options.threads;
    tab.progress = options.progress;
    Tabulated t = tabulate(source, tab);
    Compressed out;
    note_tabulation(source, t, out);
    if (dtype == TableDtype::F32)
        out.brdf = std::make_unique<TabularBrdf>(std::move(t.table), lookup);
    else
        out.brdf = std::make_unique<CompactTableBrdf>(CompactTable::encode(t.table, dtype), lookup);
    return out;
}

TableDtype dtype_option(const ReprSpec& spec) {
    return parse_table_dtype(spec.get_choice("dtype", "f32", {"f32", "f16", "u8log"}));
}

Lookup lookup_option(const ReprSpec& spec) {
    return parse_lookup(spec.get_choice("lookup", "linear", {"linear", "nearest"}));
}

// ss=N: each bin the mean of N points per axis (box filter), default 1 (point samples), as measured
// (bench/README.md, "Compact tables"): with linear lookup the box blurs what interpolation blurs again
// (3x the error of point samples for 16x16x16 on RGL's paper_white), and for bivariate tables, whose
// φd mean is a box anyway, ss=2 gained nothing on three of the four RGL materials at 4x the build time.
//
// filter=lsq: instead of the mean, the values whose linear lookup fits the ss³ points of each bin best
// (tabulate.h), default ss=3.
TabulateOptions::Filter filter_option(const ReprSpec& spec, Lookup lookup) {
    const bool lsq = spec.get_choice("filter", "box", {"box", "lsq"}) == "lsq";
    if (lsq && lookup != Lookup::Linear) throw ValueError("filter=lsq fits the linear lookup: it needs lookup=linear");
    return lsq ? TabulateOptions::Filter::LeastSquares : TabulateOptions::Filter::Box;
}

// weight=bins|solid (fit=lsq and filter=lsq): the fit's points weighed as the grid's bins (default: the
// metrics over the grid) or by their solid angle (the metrics over directions), tabulate.h.
TabulateOptions::FitWeight weight_option(const ReprSpec& spec, bool lsq) {
    if (!lsq && spec.has("weight")) throw ValueError(spec.kind() + ": weight= belongs to the least-squares fit (lsq)");
    return spec.get_choice("weight", "bins", {"bins", "solid"}) == "solid" ? TabulateOptions::FitWeight::SolidAngle
                                                                           : TabulateOptions::FitWeight::Bins;
}

int supersample_option(const ReprSpec& spec, TabulateOptions::Filter filter) {
    return spec.get_int("ss", filter == TabulateOptions::Filter::LeastSquares ? 3 : 1, 1, 16);
}

// dwarp=W: the warped θd axis (table.h, GridSpec::theta_d_warp), default 0 (linear).
double theta_d_warp_option(const ReprSpec& spec) {
    const double w = spec.get_double("dwarp", 0.0);
    if (!(w >= 0.0 && w <= GridSpec::kMaxWarp))
        throw ValueError(spec.kind() + ": dwarp=" + spec.get_string("dwarp", "") + " is outside [0, 0.95]");
    return w;
}

// symmetry=reciprocal|none (table.h): φd over [0, π), f(wi, wo) and f(wo, wi) sharing a bin (their
// mean when the source is not reciprocal), or over [0, 2π), which keeps non-reciprocal data as measured.
Symmetry symmetry_option(const ReprSpec& spec, Symmetry fallback = Symmetry::Reciprocal) {
    return parse_symmetry(spec.get_choice("symmetry", symmetry_name(fallback), {"reciprocal", "none"}));
}

// phih=N slices along φh (repr/phi_h.h), each built by build_slice from the rotated source with the
// slices' φd symmetry; the slices' notes once each.
Compressed build_phi_h(const Brdf& source, int n, PhiHSymmetry symmetry,
                       const std::function<Compressed(const Brdf&, Symmetry)>& build_slice) {
    Compressed out;
    out.brdf = tabulate_phi_h(source, n, symmetry, [&](const Brdf& slice) {
        Compressed c = build_slice(slice, slice_symmetry(symmetry));
        for (std::string& note : c.notes)
            if (std::find(out.notes.begin(), out.notes.end(), note) == out.notes.end()) out.notes.push_back(std::move(note));
        return std::move(c.brdf);
    });
    return out;
}

Compressed build_tabular(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const std::vector<int> res = spec.get_dims("res", {90, 90, 180});
    const TableDtype dtype = dtype_option(spec);
    const Lookup lookup = lookup_option(spec);
    const TabulateOptions::Filter filter = filter_option(spec, lookup);
    const int ss = supersample_option(spec, filter);
    const TabulateOptions::FitWeight weight = weight_option(spec, filter == TabulateOptions::Filter::LeastSquares);
    const double warp = theta_d_warp_option(spec);
    const int phih = spec.get_int("phih", 1, 1, GridSpec::kMaxAxis);
    const std::string symmetry = spec.get_choice("symmetry", "reciprocal", {"reciprocal", "none", "bilateral"});
    spec.finish();
    const auto table = [&](const Brdf& from, Symmetry s) {
        return build_table(from, GridSpec{res[0], res[1], res[2], BinPosition::Centre, warp, s}, {ss, ss, ss}, filter,
                           weight, dtype, lookup, options);
    };
    if (phih > 1) return build_phi_h(source, phih, parse_phi_h_symmetry(symmetry), table);
    if (symmetry == "bilateral") throw ValueError("tabular: symmetry=bilateral folds the φh axis: it needs phih >= 2");
    return table(source, parse_symmetry(symmetry));
}

// Romeiro et al. 2008's bivariate table: θh × θd, the source averaged over phi=N values of φd.
Compressed build_bivariate(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const std::vector<int> res = spec.get_dims("res", {90, 90});
    const TableDtype dtype = dtype_option(spec);
    const Lookup lookup = lookup_option(spec);
    const TabulateOptions::Filter filter = filter_option(spec, lookup);
    const int ss = supersample_option(spec, filter);
    const TabulateOptions::FitWeight weight = weight_option(spec, filter == TabulateOptions::Filter::LeastSquares);
    const int phi = spec.get_int("phi", 180, 1, GridSpec::kMaxAxis);
    const double warp = theta_d_warp_option(spec);
    // (θh, θd) do not change when wi and wo are exchanged: the φd mean is reciprocal either way, and
    // symmetry=none only spreads its phi values over [0, 2π).
    const Symmetry symmetry = symmetry_option(spec);
    spec.finish();
    return build_table(source, GridSpec{res[0], res[1], 1, BinPosition::Centre, warp, symmetry}, {ss, ss, phi}, filter,
                       weight, dtype, lookup, options);
}

FitOptions analytic_options(const ReprSpec& spec, const CompressOptions& options) {
    if (spec.positional().empty())
        throw ValueError("analytic: name the model, e.g. analytic:lambert+ggx");
    FitOptions fit_options;
    fit_options.loss = parse_fit_loss(spec.get_choice("loss", "log", {"log", "cos", "cbrt"}));
    fit_options.starts = spec.get_int("starts", fit_options.starts, 1, 1000);
    fit_options.seed = static_cast<std::uint64_t>(spec.get_int("seed", 1, 0, 1 << 30));
    spec.finish();
    fit_options.threads = options.threads;
    fit_options.progress = options.progress;
    return fit_options;
}

Compressed from_fit(FitResult fitted) {
    Compressed out;
    out.notes.push_back(std::string("fit ") + fit_status_name(fitted.report.status) + ": " + fitted.report.message);
    for (const std::string& w : fitted.report.warnings) out.notes.push_back(w);
    out.brdf = std::make_unique<AnalyticBrdf>(std::move(fitted.model));
    return out;
}

// A PCA basis lives in a file (formats/SPEC.md), so this kind reads one: the library's formats are
// part of the same target.
Compressed build_pca(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const std::string file = spec.get_string("basis", "");
    const int k = spec.get_int("k", 12, 1, 1 << 16);
    const Lookup lookup = parse_lookup(spec.get_choice("lookup", "linear", {"linear", "nearest"}));
    const bool embed = spec.get_choice("store", "reference", {"reference", "embed"}) == "embed";
    const std::optional<Symmetry> symmetry =
        spec.has("symmetry") ? std::optional<Symmetry>(symmetry_option(spec)) : std::nullopt;
    spec.finish();
    if (file.empty()) throw ValueError("pca: name the basis file (brdfz pca-train makes one), e.g. pca:basis=merl.brdfz,k=12");
    std::shared_ptr<const PcaBasis> basis = container::read_pca_basis(file);
    // The basis fixes the grid, its φd axis included: the key can only confirm it.
    if (symmetry && *symmetry != basis->grid().symmetry)
        throw ValueError("pca: symmetry=" + std::string(symmetry_name(*symmetry)) + " but basis " + file + " has symmetry " +
                         symmetry_name(basis->grid().symmetry) + " (brdfz pca-train --symmetry)");
    if (k > basis->k_max())
        throw ValueError("pca: k = " + std::to_string(k) + " but basis " + file + " has " +
                         std::to_string(basis->k_max()) + " components");
    Compressed out;
    // Projection needs the source on the basis's grid: a table already there is used as it is.
    const auto* table = dynamic_cast<const TabularBrdf*>(&source);
    std::optional<Tabulated> tabulated;
    if (!table || !(table->table().grid() == basis->grid())) {
        TabulateOptions tab;
        tab.grid = basis->grid();
        tab.threads = options.threads;
        tab.progress = options.progress;
        tabulated = tabulate(source, tab);
        note_tabulation(source, *tabulated, out);
    }
    const Table& values = tabulated ? tabulated->table : table->table();
    auto pca = std::make_unique<PcaBrdf>(basis, basis->project(values, k), lookup,
                                         embed ? PcaBrdf::BasisStorage::Embedded : PcaBrdf::BasisStorage::Referenced);
    if (pca->counts().clamped > 0)
        out.notes.push_back(std::to_string(pca->counts().clamped) + " reconstructed bins with negative values clamped to 0");
    out.brdf = std::move(pca);
    return out;
}

// svd / nmf (repr/factored.h): a table factored in a transform space. The source is factored on its
// own grid when it is a table and neither res= nor another symmetry= is given, else tabulated on res
// (default 90x90x180), with symmetry= as for tables and dwarp=W its θd axis warped as for tables (bench/README.md: satin_rosaline at 90x32x16 rank 6,
// 3.94 -> 2.96 %).
// What a factorisation did, for the user.
void note_factoring(FactorMethod method, const FactorReport& r, bool lsq, Compressed& out) {
    out.notes.push_back(std::string(factor_method_name(method)) + ": " + std::to_string(r.iterations) + " iterations, " +
                        (r.converged ? "converged" : "iteration cap reached") + ", weighted residual " +
                        std::to_string(r.residual) + " over " + std::to_string(r.valid_bins) + " valid bins");
    if (lsq)
        out.notes.push_back("fit=lsq: " + std::to_string(r.fit_iterations) + " iterations through the lookup over " +
                            std::to_string(r.fit_points) + " points, weighted residual " +
                            std::to_string(r.fit_residual_start) + " -> " + std::to_string(r.fit_residual));
    if (r.clamped > 0)
        out.notes.push_back(std::to_string(r.clamped) + " reconstructed values below 0 at the grid's samples (clamped to 0 at eval)");
}

Compressed build_factored(FactorMethod method, const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    FactorOptions fo;
    fo.method = method;
    fo.rank = spec.get_int("rank", fo.rank, 1, GridSpec::kMaxAxis);
    fo.space = parse_factor_space(spec.get_choice("space", "log", {"linear", "cos", "log", "cbrt"}));
    fo.layout = parse_factor_layout(spec.get_choice("layout", "h_dp", {"h_dp", "hd_p"}));
    fo.colour = parse_factor_colour(spec.get_choice("colour", "separate", {"separate", "shared"}));
    fo.max_iterations = spec.get_int("iterations", method == FactorMethod::Svd ? 50 : 100, 1, 100000);
    fo.fit = parse_factor_fit(spec.get_choice("fit", "samples", {"samples", "lsq"}));
    const bool lsq = fo.fit == FactorFit::LeastSquares;
    if (!lsq && (spec.has("ss") || spec.has("fit_iterations")))
        throw ValueError(spec.kind() + ": ss= and fit_iterations= belong to fit=lsq");
    fo.supersample = spec.get_int("ss", fo.supersample, 1, 16);
    fo.fit_iterations = spec.get_int("fit_iterations", fo.fit_iterations, 1, 10000);
    fo.fit_weight = weight_option(spec, lsq);
    fo.dtype = parse_factor_dtype(spec.get_choice("dtype", "f32", {"f32", "f16"}));
    const auto* tabular = dynamic_cast<const TabularBrdf*>(&source);
    const int phih = spec.get_int("phih", 1, 1, GridSpec::kMaxAxis);
    const std::string symmetry_text =
        spec.get_choice("symmetry", symmetry_name(tabular ? tabular->table().grid().symmetry : Symmetry::Reciprocal),
                        {"reciprocal", "none", "bilateral"});
    if (phih == 1 && symmetry_text == "bilateral")
        throw ValueError(spec.kind() + ": symmetry=bilateral folds the φh axis: it needs phih >= 2");
    const Symmetry symmetry = phih > 1 ? Symmetry::None : parse_symmetry(symmetry_text);
    // A φh axis tabulates each slice from the rotated source.
    const bool resample =
        phih > 1 || !tabular || spec.has("res") || symmetry != tabular->table().grid().symmetry;
    const std::vector<int> res = spec.get_dims("res", {90, 90, 180});
    const double warp = theta_d_warp_option(spec);
    if (warp != 0.0 && !resample) throw ValueError(spec.kind() + ": dwarp= applies to the res= grid; give res= as well");
    if (lsq && !resample)
        throw ValueError(spec.kind() + ": fit=lsq fits the factors on the res= grid to the source; give res= as well");
    spec.finish();
    fo.threads = options.threads;
    fo.progress = options.progress;
    const auto factor_on_grid = [&](const Brdf& from, Symmetry s) {
        Compressed out;
        TabulateOptions tab;
        tab.grid = GridSpec{res[0], res[1], res[2], BinPosition::Centre, warp, s};
        tab.grid.validate();
        tab.threads = options.threads;
        Tabulated t = tabulate(from, tab);
        note_tabulation(from, t, out);
        Factored factored = factor(from, t.table, fo);
        note_factoring(method, factored.report, lsq, out);
        out.brdf = std::move(factored.brdf);
        return out;
    };
    if (phih > 1) return build_phi_h(source, phih, parse_phi_h_symmetry(symmetry_text), factor_on_grid);
    if (resample) return factor_on_grid(source, symmetry);
    Compressed out;
    Factored factored = factor(tabular->table(), fo);
    note_factoring(method, factored.report, lsq, out);
    out.brdf = std::move(factored.brdf);
    return out;
}

Compressed build_svd(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    return build_factored(FactorMethod::Svd, source, spec, options);
}

Compressed build_nmf(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    return build_factored(FactorMethod::Nmf, source, spec, options);
}

Compressed build_analytic(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    return from_fit(fit(source, spec.positional(), analytic_options(spec, options)));
}

template <typename Build>
Compressed timed(const ReprSpec& spec, Build build) {
    const auto start = std::chrono::steady_clock::now();
    Compressed out = build();
    out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.spec = spec.str();
    return out;
}

struct Kind {
    const char* name;
    Builder build;
};

// One line per representation kind.
constexpr Kind kKinds[] = {
    {"tabular", build_tabular},
    {"bivariate", build_bivariate},
    {"analytic", build_analytic},
    {"pca", build_pca},
    {"svd", build_svd},
    {"nmf", build_nmf},
};

}  // namespace

Compressed compress(const Brdf& source, const std::string& text, const CompressOptions& options) {
    const ReprSpec spec = ReprSpec::parse(text);
    if (spec.has("phih") && spec.kind() != "tabular" && spec.kind() != "svd" && spec.kind() != "nmf")
        throw ValueError("phih is not supported by " + spec.kind() + ": only tabular, svd and nmf have a φh axis");
    for (const Kind& kind : kKinds)
        if (spec.kind() == kind.name) return timed(spec, [&] { return kind.build(source, spec, options); });
    std::string known;
    for (const Kind& kind : kKinds) known += (known.empty() ? "" : ", ") + std::string(kind.name);
    throw ValueError("unknown representation '" + spec.kind() + "' (known: " + known + ")");
}

Compressed compress(const MeasurementSet& source, const std::string& text, const CompressOptions& options) {
    const ReprSpec spec = ReprSpec::parse(text);
    if (spec.kind() != "analytic")
        throw ValueError("'" + spec.kind() + "' needs a BRDF on a grid; scattered measurements can only be fitted "
                         "(analytic:MODEL)");
    return timed(spec, [&] { return from_fit(fit(source, spec.positional(), analytic_options(spec, options))); });
}

std::vector<std::string> compress_kinds() {
    std::vector<std::string> out;
    for (const Kind& kind : kKinds) out.emplace_back(kind.name);
    return out;
}

}  // namespace brdfz
