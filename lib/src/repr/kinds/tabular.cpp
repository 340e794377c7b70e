// Kinds `tabular` (a resampled Rusinkiewicz table, repr/tabular.h, compact dtypes repr/compact_table.h)
// and `bivariate` (Romeiro et al. 2008: θh × θd, the source averaged over φd).
#include "brdfz/errors.h"
#include "brdfz/repr/tabular.h"
#include "common.h"

namespace brdfz::kinds {
namespace {

const SpecKey kDtype{"dtype", "f32", "f32|f16|u8log: stored values (u8log: 8-bit log-quantised, per-channel scale and offset)"};
const SpecKey kFilter{"filter", "box",
                      "box|lsq: each bin the mean of ss³ points, or the values whose linear lookup fits them best "
                      "(needs lookup=linear)"};
const SpecKey kSupersample{"ss", "1 (3 with filter=lsq)", "points per bin and axis, 1-16"};

// Tabulates `source` on `grid` (box-filtered by `supersample`) and keeps the table in `dtype`.
Compressed build_table(const Brdf& source, const GridSpec& grid, std::array<int, 3> supersample,
                       TabulateOptions::Filter filter, TabulateOptions::FitWeight weight, TableDtype dtype,
                       Lookup lookup, SamplerKind sampler, const CompressOptions& options) {
    TabulateOptions tab;
    tab.grid = grid;
    tab.supersample = supersample;
    tab.filter = filter;
    tab.fit_weight = weight;
    tab.threads = options.threads;
    tab.progress = options.progress;
    Compressed out;
    Tabulated t = tabulate_noted(source, tab, out);
    if (dtype == TableDtype::F32)
        out.brdf = std::make_unique<TabularBrdf>(std::move(t.table), lookup, sampler);
    else
        out.brdf = std::make_unique<CompactTableBrdf>(CompactTable::encode(t.table, dtype), lookup, sampler);
    return out;
}

TableDtype dtype_option(const ReprSpec& spec) {
    return parse_table_dtype(spec.get_choice("dtype", "f32", {"f32", "f16", "u8log"}));
}

// With linear lookup a box filter blurs what interpolation blurs again, so point samples (ss=1) are
// the default; filter=lsq instead fits the lookup to ss³ points per bin (tabulate.h).
TabulateOptions::Filter filter_option(const ReprSpec& spec, Lookup lookup) {
    const bool lsq = spec.get_choice("filter", "box", {"box", "lsq"}) == "lsq";
    if (lsq && lookup != Lookup::Linear) throw ValueError("filter=lsq fits the linear lookup: it needs lookup=linear");
    return lsq ? TabulateOptions::Filter::LeastSquares : TabulateOptions::Filter::Box;
}

int supersample_option(const ReprSpec& spec, TabulateOptions::Filter filter) {
    return spec.get_int("ss", filter == TabulateOptions::Filter::LeastSquares ? 3 : 1, 1, 16);
}

Compressed build_tabular(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) {
    const std::vector<int> res = spec.get_dims("res", {90, 90, 180});
    const TableDtype dtype = dtype_option(spec);
    const Lookup lookup = lookup_option(spec);
    const TabulateOptions::Filter filter = filter_option(spec, lookup);
    const int ss = supersample_option(spec, filter);
    const TabulateOptions::FitWeight weight = weight_option(spec, filter == TabulateOptions::Filter::LeastSquares);
    const double warp = theta_d_warp_option(spec);
    const int phih = spec.get_int("phih", 1, 1, PhiHBrdf::kMaxTableSlices);
    const std::string symmetry = phi_h_symmetry_option(spec);
    const SamplerKind sampler = sampler_option(spec);
    std::vector<std::string> notes;
    const double h_warp = theta_h_warp_option(spec, source, notes);
    spec.finish();
    const auto table = [&](const Brdf& from, Symmetry s, SamplerKind slice_sampler) {
        return build_table(from, GridSpec{res[0], res[1], res[2], BinPosition::Centre, warp, s, h_warp}, {ss, ss, ss},
                           filter, weight, dtype, lookup, slice_sampler, options);
    };
    Compressed out = phih > 1 ? build_phi_h(source, phih, parse_phi_h_symmetry(symmetry), sampler, table)
                              : table(source, parse_symmetry(symmetry), sampler);
    out.notes.insert(out.notes.begin(), notes.begin(), notes.end());
    return out;
}

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
    const Symmetry symmetry = symmetry_option(spec, "a bivariate table averages φd away");
    const SamplerKind sampler = sampler_option(spec);
    std::vector<std::string> notes;
    const double h_warp = theta_h_warp_option(spec, source, notes);
    spec.finish();
    Compressed out = build_table(source, GridSpec{res[0], res[1], 1, BinPosition::Centre, warp, symmetry, h_warp},
                                 {ss, ss, phi}, filter, weight, dtype, lookup, sampler, options);
    out.notes.insert(out.notes.begin(), notes.begin(), notes.end());
    return out;
}

}  // namespace

void register_tabular(std::vector<ReprKind>& out) {
    out.push_back({"tabular",
                   "a Rusinkiewicz (θh, θd, φd) table resampled on res, square-root θh axis (hwarp: warped by a peak)",
                   "",
                   {{"res", "90x90x180", "bins θh x θd x φd"}, kDtype, kLookupKey, kFilter, kSupersample, kWarpKey,
                    kThetaHWarpKey, kPhiHSymmetryKey, kPhiHKey, kWeightKey, kSamplerKey},
                   build_tabular});
    out.push_back({"bivariate",
                   "a (θh, θd) table without the φd axis, the source averaged over phi values of φd",
                   "",
                   {{"res", "90x90", "bins θh x θd"},
                    {"phi", "180", "φd values averaged per bin"},
                    kDtype,
                    kLookupKey,
                    kFilter,
                    kSupersample,
                    kWarpKey,
                    kThetaHWarpKey,
                    kSymmetryKey,
                    kWeightKey,
                    kSamplerKey},
                   build_bivariate});
}

}  // namespace brdfz::kinds
