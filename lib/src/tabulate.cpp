#include "brdfz/tabulate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Sparse>

#include "brdfz/errors.h"
#include "detail/fit_points.h"
#include "detail/grid_sweep.h"
#include "detail/table_lookup.h"

namespace brdfz {
namespace {

// The point-sampled table on options.grid.
Tabulated tabulate_points(const Brdf& brdf, const TabulateOptions& options) {
    const GridSpec& g = options.grid;
    Tabulated result{Table(g), {}};
    const int workers = resolve_threads(options.threads);
    std::vector<ValidityCounts> counts(workers);
    std::vector<std::size_t> extrapolated(workers, 0);
    std::vector<std::vector<Rgb>> scratch(workers);
    // Per direction, its elevation clamped as the incident one (i) and as the outgoing one (o); the
    // mirror images of the pairs evaluated (m).
    struct Clamped {
        std::vector<Vec3> wi_i, wi_o, wo_i, wo_o, wi_m, wo_m;
    };
    std::vector<Clamped> clamped(workers);
    const double theta_max = brdf.measured_theta_max();
    const bool limited = theta_max < std::numbers::pi / 2;
    const double theta_o_max = std::max(theta_max, options.outgoing_theta_max_deg * std::numbers::pi / 180.0);
    // A reciprocal grid holds f(wi, wo) and f(wo, wi) in one bin, a bilateral one f(wi, wo) and f at the
    // pair's mirror image (y → −y, φd → −φd): their mean, unless they are equal.
    const bool exchanged = g.reciprocal() && !brdf.reciprocal();
    const bool mirrored = g.bilateral() && !brdf.bilateral();
    const bool both_sides = exchanged || mirrored;
    std::vector<std::vector<Rgb>> swapped(workers);

    detail::sweep_slices(
        g, workers,
        [&](int worker, int ih, std::span<const Vec3> wi, std::span<const Vec3> wo) {
            std::vector<Rgb>& f = scratch[worker];
            f.resize(wi.size());
            if (limited) {
                Clamped& c = clamped[worker];
                for (auto* v : {&c.wi_i, &c.wi_o, &c.wo_i, &c.wo_o}) v->resize(wi.size());
                // w at elevation at most `limit`, azimuth kept; `moved` set when it was beyond.
                const auto clamp = [](const Vec3& w, double limit, bool& moved) {
                    const bool beyond = elevation(w) > limit;
                    moved = moved || beyond;
                    return beyond ? spherical_direction(limit, std::atan2(w.y, w.x)) : w;
                };
                for (std::size_t k = 0; k < wi.size(); ++k) {
                    bool moved = false;
                    c.wi_i[k] = clamp(wi[k], theta_max, moved);
                    c.wo_o[k] = clamp(wo[k], theta_o_max, moved);
                    if (exchanged) {
                        c.wo_i[k] = clamp(wo[k], theta_max, moved);
                        c.wi_o[k] = clamp(wi[k], theta_o_max, moved);
                    }
                    extrapolated[worker] += wi[k].z > 0.0 && wo[k].z > 0.0 && moved;
                }
                brdf.eval(c.wi_i, c.wo_o, f);
                if (exchanged) swapped[worker].resize(wi.size()), brdf.eval(c.wo_i, c.wi_o, swapped[worker]);
            } else {
                brdf.eval(wi, wo, f);
                if (exchanged) swapped[worker].resize(wi.size()), brdf.eval(wo, wi, swapped[worker]);
            }
            if (mirrored) {
                // The mirror image of the pair evaluated (clamping keeps azimuths, so it commutes with the mirror).
                Clamped& c = clamped[worker];
                const std::span<const Vec3> a = limited ? std::span<const Vec3>(c.wi_i) : wi,
                                            b = limited ? std::span<const Vec3>(c.wo_o) : wo;
                c.wi_m.resize(wi.size()), c.wo_m.resize(wi.size());
                for (std::size_t k = 0; k < wi.size(); ++k)
                    c.wi_m[k] = {a[k].x, -a[k].y, a[k].z}, c.wo_m[k] = {b[k].x, -b[k].y, b[k].z};
                swapped[worker].resize(wi.size());
                brdf.eval(c.wi_m, c.wo_m, swapped[worker]);
            }
            if (both_sides)
                for (std::size_t k = 0; k < wi.size(); ++k)
                    for (int c = 0; c < 3; ++c) f[k][c] = 0.5 * (f[k][c] + swapped[worker][k][c]);
            ValidityCounts& n = counts[worker];
            const std::size_t base = g.index(ih, 0, 0);
            for (std::size_t k = 0; k < wi.size(); ++k) {
                const std::size_t bin = base + k;
                if (!(wi[k].z > 0.0 && wo[k].z > 0.0)) {
                    ++n.below_horizon;  // left invalid
                    continue;
                }
                bool neg = false, nan = false, inf = false, clamped = false;
                Rgb v = f[k];
                for (double& c : v) {
                    if (std::isnan(c)) {
                        nan = true;
                    } else if (std::isinf(c) || std::isinf(static_cast<float>(c))) {
                        inf = true;
                    } else if (c < 0.0) {
                        if (options.negative == NegativePolicy::Clamp) {
                            c = 0.0;
                            clamped = true;
                        } else {
                            neg = true;
                        }
                    }
                }
                n.nan += nan;
                n.inf += inf;
                n.negative += neg;
                n.clamped += clamped;
                if (nan || inf || neg) continue;
                ++n.valid;
                result.table.set(bin, v);
            }
        },
        options.progress ? std::function<void(int, int)>([&](int done, int total) {
            options.progress(static_cast<double>(done) / total);
        })
                         : nullptr);

    for (std::size_t n : extrapolated) result.extrapolated += n;
    for (const ValidityCounts& n : counts) {
        result.counts.valid += n.valid;
        result.counts.negative += n.negative;
        result.counts.nan += n.nan;
        result.counts.inf += n.inf;
        result.counts.clamped += n.clamped;
        result.counts.below_horizon += n.below_horizon;
    }
    return result;
}

// `options` on the grid `supersample` times finer, sampled at bin centres (ValueError past the grid limits).
TabulateOptions supersampled(const TabulateOptions& options) {
    const GridSpec& g = options.grid;
    const auto [sh, sd, sp] = options.supersample;
    TabulateOptions fine = options;
    fine.grid = GridSpec{g.n_theta_h * sh, g.n_theta_d * sd, g.n_phi_d * sp, BinPosition::Centre, g.theta_d_warp, g.symmetry,
                           g.theta_h_warp};
    fine.grid.validate();
    return fine;
}

// Box filter: point-sample a grid `supersample` times finer (whose bins nest exactly in the coarse
// ones, the square-root θh axis and a warped θd axis included), then average each coarse bin's valid
// fine bins, leaving out grazing points unless the bin has no others.
Tabulated tabulate_boxes(const Brdf& brdf, const TabulateOptions& options) {
    const GridSpec& g = options.grid;
    const auto [sh, sd, sp] = options.supersample;
    Tabulated fine = tabulate_points(brdf, supersampled(options));
    const Table& f = fine.table;
    const GridSpec& fg = f.grid();
    const double min_cos = std::cos(options.box_max_theta_deg * std::numbers::pi / 180.0);
    Tabulated result{Table(g), fine.counts, fine.extrapolated};
    result.counts.valid = 0;
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                double sum[3] = {0, 0, 0}, graze_sum[3] = {0, 0, 0};
                int n = 0, graze_n = 0;
                for (int a = 0; a < sh; ++a)
                    for (int b = 0; b < sd; ++b)
                        for (int c = 0; c < sp; ++c) {
                            const int jh = ih * sh + a, jd = id * sd + b, jp = ip * sp + c;
                            const std::size_t bin = fg.index(jh, jd, jp);
                            if (!f.valid(bin)) continue;
                            const auto [wi, wo] = from_half_diff({fg.theta_h_at(jh), 0.0, fg.theta_d_at(jd), fg.phi_d_at(jp)});
                            const bool grazing = !(wi.z > min_cos && wo.z > min_cos);
                            (grazing ? graze_n : n) += 1;
                            for (int ch = 0; ch < 3; ++ch) (grazing ? graze_sum : sum)[ch] += f.at(bin, ch);
                        }
                if (n == 0 && graze_n == 0) continue;
                ++result.counts.valid;
                const double* s = n > 0 ? sum : graze_sum;
                const int m = n > 0 ? n : graze_n;
                result.table.set(g.index(ih, id, ip), {s[0] / m, s[1] / m, s[2] / m});
            }
    return result;
}

// Least squares over the points of the fine grid: minimise Σ cos²θi (f − lookup(x))² over the valid
// points (detail::fit_points, with their scales), lookup(x) being the linear lookup's weighted mean of x
// at the point's valid corners, by the normal equations. A tiny pull towards the point samples x0 (1e-9
// of the mean diagonal) keeps them positive definite and leaves bins that no point reaches at their
// point sample.
Tabulated tabulate_least_squares(const Brdf& brdf, const TabulateOptions& options) {
    const GridSpec& g = options.grid;
    Tabulated result = tabulate_points(brdf, options);  // validity, counts and x0
    // Points beyond the measured range or box_max_theta_deg weigh a tenth (a hundredth of their squared
    // error): the metrics leave them out and the source extrapolates there, so at full weight they would
    // pull the bins they share with measured points; a tenth still anchors bins that only such points
    // reach.
    constexpr double kOutsideScale = 0.1;
    const detail::FitPoints points = detail::fit_points(brdf, options, kOutsideScale);
    const Table& coarse = result.table;
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<double> rhs[3];
    int row = 0;
    for (std::size_t k = 0; k < points.wi.size(); ++k) {
        const Vec3 &wi = points.wi[k], &wo = points.wo[k];
        const detail::Corners c = detail::linear_corners(g, detail::fast_bin_coords(g, wi, wo), wi, wo);
        double w[8];
        std::size_t at[8];
        double wsum = 0.0;
        for (int i = 0; i < 8; ++i) {
            at[i] = g.index(i & 4 ? c.h.i1 : c.h.i0, i & 2 ? c.d.i1 : c.d.i0, i & 1 ? c.p.i1 : c.p.i0);
            w[i] = (i & 4 ? c.h.t : 1.0 - c.h.t) * (i & 2 ? c.d.t : 1.0 - c.d.t) * (i & 1 ? c.p.t : 1.0 - c.p.t);
            if (!coarse.valid(at[i])) w[i] = 0.0;  // the lookup skips invalid corners
            wsum += w[i];
        }
        if (!(wsum > 0.0)) continue;
        const double row_weight = wi.z * points.scale[k];
        for (int i = 0; i < 8; ++i)
            if (w[i] > 0.0) entries.emplace_back(row, static_cast<int>(at[i]), row_weight * w[i] / wsum);
        for (int ch = 0; ch < 3; ++ch) rhs[ch].push_back(row_weight * points.value[k][ch]);
        ++row;
    }

    const int n = static_cast<int>(g.bins());
    Eigen::SparseMatrix<double> a(row, n);
    a.setFromTriplets(entries.begin(), entries.end());  // repeated corners (bivariate's φd) are summed
    Eigen::SparseMatrix<double> normal = a.transpose() * a;
    const double lambda = 1e-9 * normal.diagonal().sum() / n;
    for (int j = 0; j < n; ++j) normal.coeffRef(j, j) += lambda;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) throw ValueError("tabulate: the least-squares system is singular");

    Table& out = result.table;
    std::vector<Rgb> x(static_cast<std::size_t>(n));
    for (int ch = 0; ch < 3; ++ch) {
        Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
        for (int j = 0; j < n; ++j)
            if (out.valid(static_cast<std::size_t>(j))) x0[j] = out.at(static_cast<std::size_t>(j), ch);
        const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(rhs[ch].data(), row);
        const Eigen::VectorXd solved = solver.solve(a.transpose() * b + lambda * x0);
        for (int j = 0; j < n; ++j) x[static_cast<std::size_t>(j)][ch] = solved[j];
    }
    result.counts.clamped = 0;
    for (std::size_t j = 0; j < x.size(); ++j) {
        if (!out.valid(j)) continue;
        bool clamped = false;
        for (double& v : x[j]) {
            clamped = clamped || v < 0.0;
            v = std::fmax(v, 0.0);
        }
        result.counts.clamped += clamped;
        out.set(j, x[j]);
    }
    return result;
}

}  // namespace

namespace detail {

FitPoints fit_points(const Brdf& brdf, const TabulateOptions& options, double outside_scale) {
    const GridSpec& g = options.grid;
    const TabulateOptions fine_options = supersampled(options);
    const GridSpec& fg = fine_options.grid;
    if (fg.bins() > kMaxFitPoints)
        throw ValueError("least squares over " + std::to_string(fg.bins()) +
                         " points (more than 2^21); lower the supersampling or the resolution");
    const Tabulated fine = tabulate_points(brdf, fine_options);

    // On a warped θd axis the points crowd towards grazing: dθd/du relative to the linear axis.
    std::vector<double> density(static_cast<std::size_t>(fg.n_theta_d), 1.0);
    if (fg.theta_d_warp != 0.0)
        for (int jd = 0; jd < fg.n_theta_d; ++jd) {
            const double w = fg.theta_d_warp, t = fg.theta_d_at(jd);
            density[jd] = std::sqrt(2.0 / std::numbers::pi / ((1.0 - w) * 2.0 / std::numbers::pi + w * std::sin(t)));
        }
    // On a warped θh axis they crowd towards the pole: dθh/du relative to the square-root axis.
    std::vector<double> density_h(static_cast<std::size_t>(fg.n_theta_h), 1.0);
    if (fg.theta_h_warp != 0.0)
        for (int jh = 0; jh < fg.n_theta_h; ++jh)
            density_h[jh] = std::sqrt(axis::theta_h_density(jh + fg.sample_offset(), fg.n_theta_h, fg.theta_h_warp));
    // Weighing by solid angle: dωi dωo = 4 cosθd sinθd sinθh dθh dθd dφh dφd, with dθh/du the axis's
    // slope (∝ u on the square-root axis; dθd/du is in `density`); the square root, as the scale
    // multiplies a residual. Normalised to a mean of 1 over the points, so that the outside share keeps
    // its meaning.
    const bool solid = options.fit_weight == TabulateOptions::FitWeight::SolidAngle;
    const auto solid_scale = [&](int jh, int jd) {
        const double th = fg.theta_h_at(jh), td = fg.theta_d_at(jd);
        return std::sqrt(std::sin(th) * axis::theta_h_slope(jh + 0.5, fg.n_theta_h, fg.theta_h_warp) * std::sin(td) *
                         std::cos(td));
    };
    // Outside: beyond the cut, or evaluated at a clamped incident elevation (wo too where the bin holds
    // (wo, wi) as well).
    const double min_cos = std::cos(options.box_max_theta_deg * std::numbers::pi / 180.0);
    const double measured_cos = std::cos(brdf.measured_theta_max());
    const bool both_sides = g.reciprocal() && !brdf.reciprocal();
    FitPoints points;
    for (int jh = 0; jh < fg.n_theta_h; ++jh)
        for (int jd = 0; jd < fg.n_theta_d; ++jd)
            for (int jp = 0; jp < fg.n_phi_d; ++jp) {
                const std::size_t bin = fg.index(jh, jd, jp);
                if (!fine.table.valid(bin)) continue;
                const auto [wi, wo] = from_half_diff({fg.theta_h_at(jh), 0.0, fg.theta_d_at(jd), fg.phi_d_at(jp)});
                const bool outside = !(wi.z > min_cos && wo.z > min_cos) || !(wi.z >= measured_cos) ||
                                     (both_sides && !(wo.z >= measured_cos));
                points.wi.push_back(wi);
                points.wo.push_back(wo);
                points.value.push_back({fine.table.at(bin, 0), fine.table.at(bin, 1), fine.table.at(bin, 2)});
                points.scale.push_back(density[jd] * (solid ? solid_scale(jh, jd) : density_h[jh]) *
                                       (outside ? outside_scale : 1.0));
            }
    if (solid && !points.scale.empty()) {
        double mean_sq = 0.0;
        for (double s : points.scale) mean_sq += s * s;
        const double norm = std::sqrt(points.scale.size() / mean_sq);
        for (double& s : points.scale) s *= norm;
    }
    return points;
}

}  // namespace detail

Tabulated tabulate(const Brdf& brdf, const TabulateOptions& options) {
    options.grid.validate();
    if (!(options.outgoing_theta_max_deg > 0.0 && options.outgoing_theta_max_deg <= 90.0))
        throw ValueError("tabulate: outgoing_theta_max_deg must be in (0, 90]");
    const auto [sh, sd, sp] = options.supersample;
    if (sh < 1 || sd < 1 || sp < 1)
        throw ValueError("tabulate: supersampling factors must be >= 1");
    if (sh == 1 && sd == 1 && sp == 1) return tabulate_points(brdf, options);
    if (!(options.box_max_theta_deg > 0.0 && options.box_max_theta_deg <= 90.0))
        throw ValueError("tabulate: box_max_theta_deg must be in (0, 90]");
    if (options.grid.position != BinPosition::Centre)
        throw ValueError("tabulate: supersampling averages over whole bins, so it needs bin centres");
    return options.filter == TabulateOptions::Filter::LeastSquares ? tabulate_least_squares(brdf, options)
                                                                    : tabulate_boxes(brdf, options);
}

}  // namespace brdfz
