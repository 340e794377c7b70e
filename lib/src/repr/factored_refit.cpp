// factor(source, table, options) with fit=lsq (factored.h): the sample fit's factors refitted to the
// source through eval's interpolation, by alternating weighted least squares on sparse normal equations.
#include <Eigen/Cholesky>
#include <Eigen/Sparse>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "brdfz/errors.h"
#include "detail/fit_points.h"
#include "detail/parallel.h"
#include "detail/table_lookup.h"
#include "repr/factored_impl.h"
#include "repr/factored_solve.h"

namespace brdfz {
namespace {

using Mat = detail::FactorMat;
using Vec = detail::FactorVec;
using detail::Solved;

// ---------------------------------------------------------------------------------------------
// Fit through the lookup (fit=lsq)

// What the refit sees of each point: its values in the transform space and its weight (the squared row
// scale of detail::fit_points, times cos²θi in cos space).
struct LookupPoints {
    std::vector<std::array<double, 3>> y;
    std::vector<double> w;
};

// One factor as the points read it: per point, the `corners` rows eval's blend reads and their weights,
// and the block pattern of that factor's normal equations (the row pairs any point couples, sorted),
// with each point's corner pairs as indices into it.
struct LookupSide {
    int rows = 0, corners = 0;
    std::vector<int> row;                            // points × corners
    std::vector<double> weight;                      // points × corners
    std::vector<std::pair<int, int>> blocks;         // (q, q'), both orders
    std::vector<int> slot;                           // points × corners²

    // The interpolated factor row at point p: Σ_r weight_r · f.row(row_r).
    template <typename Out>
    void blend(const Mat& f, std::size_t p, Out& out) const {
        out = weight[p * corners] * f.row(row[p * corners]);
        for (int r = 1; r < corners; ++r) out += weight[p * corners + r] * f.row(row[p * corners + r]);
    }
};

// The refit's chunks of points: a fixed split, so results do not depend on the thread count; few,
// because each holds a copy of the normal equations' blocks.
constexpr int kFitChunks = 4;
// Bounds on one factor's normal equations (doubles in the blocks: 32 MiB per chunk) and unknowns.
constexpr std::size_t kMaxFitEntries = std::size_t{1} << 22, kMaxFitUnknowns = std::size_t{1} << 18;

// Refuses (before any work) a refit whose points or normal equations exceed the bounds: a factor row
// couples with at most 3 rows along a 1-D axis of the grid and 9 on a 2-D one.
void check_fit_size(const Factors& f, int supersample, const char* method) {
    const std::size_t ss = static_cast<std::size_t>(supersample);
    const std::size_t points = f.grid.bins() * ss * ss * ss;
    if (points > detail::kMaxFitPoints)
        throw ValueError(std::string(method) + " fit=lsq: least squares over " + std::to_string(points) +
                         " points (more than 2^21); lower ss= or the resolution");
    const std::size_t m = static_cast<std::size_t>(f.row_width());
    const bool hxdp = f.layout == FactorLayout::HxDP;
    const std::size_t sides[2][2] = {{static_cast<std::size_t>(f.rows()), hxdp ? 3u : 9u},
                                     {static_cast<std::size_t>(f.columns()), hxdp ? 9u : 3u}};
    for (const auto& [rows, neighbours] : sides)
        if (rows * m > kMaxFitUnknowns || rows * neighbours * m * m > kMaxFitEntries)
            throw ValueError(std::string(method) + " fit=lsq: a factor's normal equations would have " +
                             std::to_string(rows * m) + " unknowns and up to " + std::to_string(rows * neighbours * m * m) +
                             " entries (at most 2^18 and 2^22); lower the rank or the resolution");
}

LookupSide lookup_side(int rows, int corners, std::vector<int> row, std::vector<double> weight) {
    LookupSide s;
    s.rows = rows;
    s.corners = corners;
    s.row = std::move(row);
    s.weight = std::move(weight);
    const std::size_t points = s.row.size() / static_cast<std::size_t>(corners);
    std::vector<std::int64_t> keys;
    keys.reserve(points * corners * corners);
    for (std::size_t p = 0; p < points; ++p)
        for (int a = 0; a < corners; ++a)
            for (int b = 0; b < corners; ++b)
                keys.push_back(std::int64_t{s.row[p * corners + a]} * rows + s.row[p * corners + b]);
    std::vector<std::int64_t> unique = keys;
    std::sort(unique.begin(), unique.end());
    unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
    for (std::int64_t k : unique) s.blocks.emplace_back(static_cast<int>(k / rows), static_cast<int>(k % rows));
    s.slot.resize(keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i)
        s.slot[i] = static_cast<int>(std::lower_bound(unique.begin(), unique.end(), keys[i]) - unique.begin());
    return s;
}

// min ½ xᵀAx − bᵀx subject to x ≥ 0 by projected Gauss-Seidel from the given x (A symmetric positive
// definite, both triangles stored): nmf's step on the sparse normal equations, warm-started.
void nnls(const Eigen::SparseMatrix<double>& a, const Vec& b, Vec& x) {
    const Vec diagonal = a.diagonal();
    for (int sweep = 0; sweep < 200; ++sweep) {
        double change = 0.0, scale = 0.0;
        for (Eigen::Index i = 0; i < a.outerSize(); ++i) {
            double ax = 0.0;
            for (Eigen::SparseMatrix<double>::InnerIterator it(a, i); it; ++it) ax += it.value() * x[it.index()];
            const double next = std::max(0.0, x[i] + (b[i] - ax) / diagonal[i]);
            change = std::max(change, std::fabs(next - x[i]));
            x[i] = next;
            scale = std::max(scale, next);
        }
        if (change <= 1e-9 * scale) break;
    }
}

// Updates every row of x (side xs) given the other factor y (side ys) and the mix (3 × m: colour
// weights, or separate colour's one-hot selection): minimises
//   Σ_p w_p Σ_c (y_pc − Σ_j mix_cj x̃_pj ỹ_pj)² + λ |x − x_prev|²
// where x̃, ỹ blend the rows eval reads. Point p's rows of x enter with the design vectors
// a_r · (mix_c ∘ ỹ_p), so its normal-equation block for rows (q, q') is a_q a_q' w_p diag(ỹ) MᵀM diag(ỹ).
// λ = 1e-6 of the mean diagonal: keeps the system definite and leaves rows no point reaches where
// they were. nmf: x ≥ 0 (projected Gauss-Seidel).
void lookup_step(Mat& x, const LookupSide& xs, const Mat& y, const LookupSide& ys, const Mat& mix,
                 const LookupPoints& pts, bool nonneg, int threads, const char* method) {
    const Eigen::Index m = x.cols();
    const std::size_t points = pts.w.size(), nblocks = xs.blocks.size();
    const Eigen::MatrixXd s2 = mix.transpose() * mix;
    struct Acc {
        std::vector<double> blocks;  // nblocks × m × m
        Mat rhs;                     // rows × m
    };
    std::vector<Acc> acc(kFitChunks);
    detail::parallel_for(kFitChunks, threads, [&](int, int chunk) {
        Acc& a = acc[chunk];
        a.blocks.assign(nblocks * m * m, 0.0);
        a.rhs = Mat::Zero(xs.rows, m);
        Eigen::RowVectorXd other(m), z(m), r(m);
        Eigen::MatrixXd g(m, m);
        const std::size_t begin = points * chunk / kFitChunks, end = points * (chunk + 1) / kFitChunks;
        for (std::size_t p = begin; p < end; ++p) {
            ys.blend(y, p, other);
            const Eigen::Vector3d yp(pts.y[p][0], pts.y[p][1], pts.y[p][2]);
            z = yp.transpose() * mix;  // Σ_c y_c mix_c
            r = pts.w[p] * other.cwiseProduct(z);
            g = pts.w[p] * (other.transpose() * other).cwiseProduct(s2);
            const int nc = xs.corners;
            for (int i = 0; i < nc; ++i) {
                const double wi = xs.weight[p * nc + i];
                a.rhs.row(xs.row[p * nc + i]) += wi * r;
                for (int k = 0; k < nc; ++k) {
                    const double wik = wi * xs.weight[p * nc + k];
                    if (wik == 0.0) continue;
                    Eigen::Map<Eigen::MatrixXd>(a.blocks.data() + xs.slot[(p * nc + i) * nc + k] * m * m, m, m) += wik * g;
                }
            }
        }
    });
    for (int c = 1; c < kFitChunks; ++c) {
        for (std::size_t i = 0; i < acc[0].blocks.size(); ++i) acc[0].blocks[i] += acc[c].blocks[i];
        acc[0].rhs += acc[c].rhs;
    }
    const Eigen::Index n = static_cast<Eigen::Index>(xs.rows) * m;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(nblocks * m * m + n);
    double trace = 0.0;
    for (std::size_t b = 0; b < nblocks; ++b) {
        const auto [q, q2] = xs.blocks[b];
        const double* block = acc[0].blocks.data() + b * m * m;  // column-major m × m
        for (Eigen::Index j = 0; j < m; ++j)
            for (Eigen::Index i = 0; i < m; ++i) {
                entries.emplace_back(q * m + i, q2 * m + j, block[j * m + i]);
                if (q == q2 && i == j) trace += block[j * m + i];
            }
    }
    const double lambda = 1e-6 * trace / static_cast<double>(n) + 1e-300;
    for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, lambda);
    Eigen::SparseMatrix<double> normal(n, n);
    normal.setFromTriplets(entries.begin(), entries.end());
    Vec previous = Eigen::Map<const Vec>(x.data(), n);  // row-major: row q's m entries together
    const Vec rhs = Eigen::Map<const Vec>(acc[0].rhs.data(), n) + lambda * previous;
    if (nonneg) {
        nnls(normal, rhs, previous);
        Eigen::Map<Vec>(x.data(), n) = previous;
        return;
    }
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
    if (ldlt.info() != Eigen::Success) throw ValueError(std::string(method) + " fit=lsq: the normal equations are singular");
    Eigen::Map<Vec>(x.data(), n) = ldlt.solve(rhs);
}

// The colour weights' normal equations over the points, K = Σ w (ũ∘ṽ)(ũ∘ṽ)ᵀ and r_c = Σ w y_c (ũ∘ṽ),
// and Σ w y_c²: enough for the weights' update and the objective Σ_c (yy_c − 2 s_cᵀ r_c + s_cᵀ K s_c).
struct MixSums {
    Eigen::MatrixXd k;
    Eigen::MatrixXd r;  // m × 3
    double yy = 0.0;
    double objective(const Mat& mix) const {
        double sum = yy;
        for (int c = 0; c < 3; ++c) {
            const Vec s = mix.row(c).transpose();
            sum += s.dot(k * s) - 2.0 * s.dot(r.col(c));
        }
        return std::max(0.0, sum);
    }
};

MixSums mix_sums(const Mat& u, const LookupSide& us, const Mat& v, const LookupSide& vs, const LookupPoints& pts,
                 int threads) {
    const Eigen::Index m = u.cols();
    const std::size_t points = pts.w.size();
    std::vector<MixSums> acc(kFitChunks);
    detail::parallel_for(kFitChunks, threads, [&](int, int chunk) {
        MixSums& a = acc[chunk];
        a.k = Eigen::MatrixXd::Zero(m, m);
        a.r = Eigen::MatrixXd::Zero(m, 3);
        Eigen::RowVectorXd uu(m), vv(m);
        Vec q(m);
        for (std::size_t p = points * chunk / kFitChunks; p < points * (chunk + 1) / kFitChunks; ++p) {
            us.blend(u, p, uu);
            vs.blend(v, p, vv);
            q = uu.cwiseProduct(vv).transpose();
            a.k.selfadjointView<Eigen::Lower>().rankUpdate(q, pts.w[p]);
            for (int c = 0; c < 3; ++c) {
                a.r.col(c) += pts.w[p] * pts.y[p][c] * q;
                a.yy += pts.w[p] * pts.y[p][c] * pts.y[p][c];
            }
        }
    });
    MixSums total = std::move(acc[0]);
    for (int c = 1; c < kFitChunks; ++c) {
        total.k += acc[c].k;
        total.r += acc[c].r;
        total.yy += acc[c].yy;
    }
    const Eigen::MatrixXd full = total.k.selfadjointView<Eigen::Lower>();
    total.k = full;
    return total;
}

// Shared colour: the weights s_c minimising the objective given U and V (≥ 0 for nmf).
void update_mix(Mat& mix, const MixSums& sums, bool nonneg) {
    Eigen::MatrixXd kk = sums.k;
    kk.diagonal().array() += 1e-10 * sums.k.trace() / static_cast<double>(kk.rows()) + 1e-300;
    for (int c = 0; c < 3; ++c) {
        Vec s = mix.row(c).transpose();
        if (nonneg)
            detail::nnls(kk, Vec(sums.r.col(c)), s);
        else
            s = kk.ldlt().solve(sums.r.col(c));
        mix.row(c) = s.transpose();
    }
}

double to_f16(double x) { return static_cast<float>(Eigen::half(static_cast<float>(x))); }

// fit=lsq's outside points (tabulate.h): a tenth of the row scale, as filter=lsq weighs them.
constexpr double kOutsideScale = 0.1;

// The refit of fit=lsq (factored.h), from the sample fit's factors `start`. r.s holds the mix.
void refit(const Brdf& source, const Factors& start, const FactorOptions& o, Solved& r, FactorReport& report,
           std::array<float, 3>& top) {
    const char* method = factor_method_name(o.method);
    const GridSpec& g = start.grid;
    const bool nonneg = o.method == FactorMethod::Nmf, shared = o.colour == FactorColour::Shared;
    const int m = start.row_width(), k = start.rank, rows = start.rows(), cols = start.columns();
    using FloatRows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    r.u = Eigen::Map<const FloatRows>(start.u.data(), rows, m).cast<double>();
    r.v = Eigen::Map<const FloatRows>(start.v.data(), cols, m).cast<double>();
    r.s = Mat::Zero(3, m);
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < k; ++j)
            if (shared)
                r.s(c, j) = start.colour_weights[static_cast<std::size_t>(c) * k + j];
            else
                r.s(c, c * k + j) = 1.0;

    TabulateOptions tab;
    tab.grid = g;
    tab.supersample = {o.supersample, o.supersample, o.supersample};
    tab.fit_weight = o.fit_weight;
    tab.threads = o.threads;
    const detail::FitPoints fp = detail::fit_points(source, tab, kOutsideScale);
    const std::size_t points = fp.wi.size();
    if (points == 0) throw ValueError(std::string(method) + " fit=lsq: no valid points to fit");
    LookupPoints pts;
    pts.y.resize(points);
    pts.w.resize(points);
    const bool hxdp = o.layout == FactorLayout::HxDP;
    const int uc = hxdp ? 2 : 4, vc = hxdp ? 4 : 2;
    std::vector<int> urow(points * uc), vrow(points * vc);
    std::vector<double> uw(points * uc), vw(points * vc);
    for (std::size_t p = 0; p < points; ++p) {
        const Vec3 &wi = fp.wi[p], &wo = fp.wo[p];
        const double cos_i = o.space == FactorSpace::Cos ? wi.z : 1.0;
        pts.w[p] = fp.scale[p] * fp.scale[p] * cos_i * cos_i;
        for (int c = 0; c < 3; ++c) {
            pts.y[p][c] = detail::to_space(o.space, fp.value[p][c]);
            top[c] = std::max(top[c], static_cast<float>(fp.value[p][c]));
        }
        // Eval's corners (set_corners): the 1-D axis's two rows, the 2-D axis's four (outer a, inner b).
        const detail::Corners s = detail::linear_corners(g, detail::fast_bin_coords(g, wi, wo), wi, wo);
        const auto one = [&](const detail::Span& a, int* row, double* w) {
            row[0] = a.i0, row[1] = a.i1, w[0] = 1.0 - a.t, w[1] = a.t;
        };
        const auto two = [&](const detail::Span& a, const detail::Span& b, int inner, int* row, double* w) {
            row[0] = a.i0 * inner + b.i0, row[1] = a.i0 * inner + b.i1;
            row[2] = a.i1 * inner + b.i0, row[3] = a.i1 * inner + b.i1;
            w[0] = (1.0 - a.t) * (1.0 - b.t), w[1] = (1.0 - a.t) * b.t, w[2] = a.t * (1.0 - b.t), w[3] = a.t * b.t;
        };
        if (hxdp) {
            one(s.h, &urow[p * uc], &uw[p * uc]);
            two(s.d, s.p, g.n_phi_d, &vrow[p * vc], &vw[p * vc]);
        } else {
            two(s.h, s.d, g.n_theta_d, &urow[p * uc], &uw[p * uc]);
            one(s.p, &vrow[p * vc], &vw[p * vc]);
        }
    }
    const LookupSide us = lookup_side(rows, uc, std::move(urow), std::move(uw));
    const LookupSide vs = lookup_side(cols, vc, std::move(vrow), std::move(vw));
    report.fit_points = points;

    MixSums sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
    const double norm = sums.yy;
    double objective = sums.objective(r.s);
    report.fit_residual_start = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
    for (int it = 1; it <= o.fit_iterations; ++it) {
        lookup_step(r.u, us, r.v, vs, r.s, pts, nonneg, o.threads, method);
        lookup_step(r.v, vs, r.u, us, r.s, pts, nonneg, o.threads, method);
        sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
        if (shared) update_mix(r.s, sums, nonneg);
        const double previous = objective;
        objective = sums.objective(r.s);
        detail::balance(r, shared);
        report.fit_iterations = it;
        if (!std::isfinite(objective) || !r.u.allFinite() || !r.v.allFinite() || !r.s.allFinite())
            throw ValueError(std::string(method) + " fit=lsq: the refit diverged (non-finite values after " +
                             std::to_string(it) + " iterations)");
        if (o.progress) o.progress(0.25 + 0.75 * it / o.fit_iterations);
        if (previous - objective <= o.tolerance * previous) break;
    }
    if (o.dtype == FactorDtype::F16) {
        // Round U, refit V to the rounded U, round V, refit the (float32) colour weights.
        detail::scale_for_f16(r, shared);
        r.u = r.u.unaryExpr([](double x) { return to_f16(x); });
        lookup_step(r.v, vs, r.u, us, r.s, pts, nonneg, o.threads, method);
        r.v = r.v.unaryExpr([](double x) { return to_f16(x); });
        sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
        if (shared) update_mix(r.s, sums, nonneg);
        objective = sums.objective(r.s);
    }
    report.fit_residual = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
}

}  // namespace

Factored factor(const Brdf& source, const Table& table, const FactorOptions& o) {
    if (o.fit == FactorFit::Samples) return factor(table, o);
    const char* method = factor_method_name(o.method);
    if (o.fit_iterations < 1) throw ValueError(std::string(method) + ": the refit's iteration cap must be at least 1");
    if (o.supersample < 1 || o.supersample > 16)
        throw ValueError(std::string(method) + ": fit=lsq's supersampling must be in [1, 16]");
    Factors shape;
    shape.grid = table.grid();
    shape.layout = o.layout;
    shape.colour = o.colour;
    shape.rank = o.rank;
    check_fit_size(shape, o.supersample, method);
    FactorOptions first = o;
    first.fit = FactorFit::Samples;
    first.dtype = FactorDtype::F32;
    first.sampler = SamplerKind::None;  // the refit's start: its factors alone are used
    if (o.progress) first.progress = [&o](double x) { o.progress(0.25 * x); };
    const Factored start = factor(table, first);
    Factors f = start.brdf->factors();
    FactorReport report = start.report;
    Solved r;
    refit(source, f, o, r, report, f.max_value);
    f.dtype = o.dtype;
    const bool shared = o.colour == FactorColour::Shared;
    const int m = f.row_width();
    for (int i = 0; i < f.rows(); ++i)
        for (int j = 0; j < m; ++j) f.u[static_cast<std::size_t>(i) * m + j] = static_cast<float>(r.u(i, j));
    for (int i = 0; i < f.columns(); ++i)
        for (int j = 0; j < m; ++j) f.v[static_cast<std::size_t>(i) * m + j] = static_cast<float>(r.v(i, j));
    if (shared)
        for (int c = 0; c < 3; ++c)
            for (int j = 0; j < f.rank; ++j)
                f.colour_weights[static_cast<std::size_t>(c) * f.rank + j] = static_cast<float>(r.s(c, j));
    Factored out{std::make_unique<FactoredBrdf>(std::move(f), o.sampler), report};
    out.brdf->reconstruct(&out.report.clamped);
    return out;
}

}  // namespace brdfz
