// Kinds `svd` and `nmf` (repr/factored.h): a table factored in a transform space, on the source's own
// grid when it is a table and neither res= nor another symmetry= is given, else tabulated on res; with
// phih=N, one factorisation per φh slice of the source (repr/phi_h.h), each tabulated on res.
#include "brdfz/errors.h"
#include "brdfz/repr/factored.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace brdfz::kinds {
namespace {

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
    const SamplerKind sampler = sampler_option(spec);
    const Table* table = source.stored_table();
    const int phih = spec.get_int("phih", 1, 1, PhiHBrdf::kMaxFactoredSlices);
    const std::string symmetry_text =
        phi_h_symmetry_option(spec, table ? table->grid().symmetry : Symmetry::Reciprocal);
    const Symmetry symmetry = phih > 1 ? Symmetry::None : parse_symmetry(symmetry_text);
    // A φh axis tabulates each slice from the rotated source.
    const bool resample = phih > 1 || !table || spec.has("res") || symmetry != table->grid().symmetry;
    const std::vector<int> res = spec.get_dims("res", {90, 90, 180});
    const double warp = theta_d_warp_option(spec);
    if (warp != 0.0 && !resample) throw ValueError(spec.kind() + ": dwarp= applies to the res= grid; give res= as well");
    std::vector<std::string> notes;
    const double h_warp = theta_h_warp_option(spec, source, notes);
    if (h_warp != 0.0 && !resample)
        throw ValueError(spec.kind() + ": hwarp= applies to the res= grid; give res= as well");
    if (lsq && !resample)
        throw ValueError(spec.kind() + ": fit=lsq fits the factors on the res= grid to the source; give res= as well");
    spec.finish();
    fo.threads = options.threads;
    fo.progress = options.progress;
    const auto factor_on_grid = [&](const Brdf& from, Symmetry s, SamplerKind slice_sampler) {
        Compressed out;
        TabulateOptions tab;
        tab.grid = GridSpec{res[0], res[1], res[2], BinPosition::Centre, warp, s, h_warp};
        tab.threads = options.threads;
        const Tabulated t = tabulate_noted(from, tab, out);
        FactorOptions slice_options = fo;
        slice_options.sampler = slice_sampler;
        Factored factored = factor(from, t.table, slice_options);
        note_factoring(method, factored.report, lsq, out);
        out.brdf = std::move(factored.brdf);
        return out;
    };
    if (resample) {
        Compressed out = phih > 1 ? build_phi_h(source, phih, parse_phi_h_symmetry(symmetry_text), sampler, factor_on_grid)
                                  : factor_on_grid(source, symmetry, sampler);
        out.notes.insert(out.notes.begin(), notes.begin(), notes.end());
        return out;
    }
    Compressed out;
    fo.sampler = sampler;
    Factored factored = factor(*table, fo);
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

std::vector<SpecKey> keys(const char* iterations) {
    return {{"rank", "4", "factor rank K"},
            {"space", "log", "linear|cos|log|cbrt: the transform space factored"},
            {"layout", "h_dp", "h_dp|hd_p: rows θh x columns (θd, φd), or (θh, θd) x φd"},
            {"colour", "separate", "separate|shared: a product per channel, or one with per-channel weights"},
            {"iterations", iterations, "iteration cap of the factorisation"},
            {"res", "(a table source's own grid, else 90x90x180)", "bins θh x θd x φd the source is tabulated on"},
            kWarpKey,
            kThetaHWarpKey,
            {"fit", "samples", "samples|lsq: factor the grid's samples, or refit through eval's interpolation (needs res)"},
            {"ss", "2", "fit=lsq: points per bin and axis, 1-16"},
            {"fit_iterations", "20", "fit=lsq: the refit's iteration cap"},
            {"dtype", "f32", "f32|f16: stored factors (f16: half the bytes)"},
            {"symmetry", "(a table source's own, else reciprocal)", kPhiHSymmetryKey.help},
            kPhiHKey,
            kWeightKey,
            kSamplerKey};
}

}  // namespace

void register_factored(std::vector<ReprKind>& out) {
    out.push_back({"svd", "a low-rank factorisation (masked least squares) in a transform space", "", keys("50"),
                   build_svd});
    out.push_back({"nmf", "a non-negative factorisation, so reconstructions stay >= 0 (Lawrence et al. 2004)", "",
                   keys("100"), build_nmf});
}

}  // namespace brdfz::kinds
