// factor(table, options) (factored.h): the factors fitted to the table's samples by alternating weighted
// least squares on Eigen.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/parallel.h"
#include "repr/factored_impl.h"
#include "repr/factored_solve.h"

namespace brdfz {
namespace {

// ---------------------------------------------------------------------------------------------
// Factorisation: alternating weighted least squares

using Mat = detail::FactorMat;
using Vec = detail::FactorVec;
using detail::Solved;

// What one side of an alternating step needs, row i of each matrix being row i of that side's factor
// (the other side sees the transposes). Row-major, so a row is contiguous.
struct Side {
    Mat w;                // weights: 0 for invalid bins
    std::vector<Mat> wx;  // per channel: w ∘ y
    Vec xx;               // per row: Σ_c Σ_j w y², for the objective
};

// Normal equations of the colour weights s, accumulated while updating V (shared colour only).
struct ColourSums {
    Eigen::MatrixXd k;   // Σ_j (v_j v_jᵀ) ∘ G_j
    std::vector<Vec> r;  // per channel: Σ_j v_j ∘ (Uᵀ (w_j ∘ y_cj))
    double objective = 0.0;
};

constexpr int kChunks = 32;  // fixed work split, so results do not depend on the thread count
// Small enough that a masked table factored at full rank is still reproduced to float precision,
// large enough to bound the extrapolation into invalid bins of a log-space factorisation.
constexpr double kRidge = 1e-5;

// Updates every row of `out` given the other factor F: row i minimises
//   Σ_c Σ_j w_ij (y_cij − Σ_a out_ia s_ca F_ja)² + Σ_a λ_ia out_ia²
// (non-negatively for nmf). In log and cbrt space the ridge λ_ia is `ridge` times what row i's
// diagonal of the normal equations lacks of the mean over rows (0 for a row as well measured as the
// average, so a fully valid table is factored exactly): a row with few valid bins, or nearly
// collinear ones, has its undetermined directions pulled towards 0 instead of fitting its few values
// with large opposite components, which extrapolate into the invalid bins and there, through expm1
// or the cube, far beyond the data (RGL cc_ibiza_sunset at grazing θd, nmf rank 2, log space: values
// past e^700). In linear and cos space the extrapolation stays linear, eval's ceiling bounds it, and
// a ridge would only cost accuracy where the data determine the factors, so
// `ridge` is 0 there. Rows without any valid bin come out 0. A ridge of 1e-10 of the row's own
// diagonal keeps the equations definite. Its normal equations are G_i ∘ (Σ_c s_c s_cᵀ)
// with G_i = Σ_j w_ij F_j F_jᵀ: for all rows at once, one product W·P with P_j = vec(F_j F_jᵀ), and
// the right-hand sides (W ∘ Y_c)·F. Returns the objective after the update and the colour weights'
// normal equations.
ColourSums update_side(Mat& out, const Mat& other, const Side& side, const Mat& s, bool nonneg, double ridge,
                       int threads) {
    const Eigen::Index n = out.rows(), k = out.cols(), m = other.rows();
    const int channels = static_cast<int>(side.wx.size());
    Eigen::MatrixXd s2 = Eigen::MatrixXd::Zero(k, k);
    for (int c = 0; c < channels; ++c) s2 += s.row(c).transpose() * s.row(c);
    Mat outer(m, k * k);
    for (Eigen::Index j = 0; j < m; ++j)
        for (Eigen::Index a = 0; a < k; ++a)
            for (Eigen::Index b = 0; b < k; ++b) outer(j, a * k + b) = other(j, a) * other(j, b);
    // Mean over rows of diag(G_i ∘ s2): Σ_j (Σ_i w_ij) F_ja² · s2_aa / n.
    const Vec mean_diagonal = (other.cwiseAbs2().transpose() * side.w.colwise().sum().transpose())
                                  .cwiseProduct(s2.diagonal()) / static_cast<double>(n);

    const int chunks = static_cast<int>(std::min<Eigen::Index>(n, kChunks));
    std::vector<ColourSums> sums(chunks);
    detail::parallel_for(chunks, threads, [&](int, int chunk) {
        const Eigen::Index begin = n * chunk / chunks, len = n * (chunk + 1) / chunks - begin;
        const Mat grams = side.w.middleRows(begin, len) * outer;
        std::vector<Mat> rhs(channels);
        for (int c = 0; c < channels; ++c) rhs[c] = side.wx[c].middleRows(begin, len) * other;
        ColourSums& acc = sums[chunk];
        acc.k = Eigen::MatrixXd::Zero(k, k);
        acc.r.assign(channels, Vec::Zero(k));
        Eigen::MatrixXd g(k, k), a(k, k), ridged(k, k);
        Vec b(k), u(k);
        Eigen::LDLT<Eigen::MatrixXd> ldlt(k);
        for (Eigen::Index r = 0; r < len; ++r) {
            g = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                grams.row(r).data(), k, k);
            b.setZero();
            for (int c = 0; c < channels; ++c) b += s.row(c).transpose().cwiseProduct(rhs[c].row(r).transpose());
            a = g.cwiseProduct(s2);
            ridged = a;
            ridged.diagonal() += ridge * (mean_diagonal - a.diagonal()).cwiseMax(0.0);
            ridged.diagonal().array() += 1e-10 * a.trace() / static_cast<double>(k) + 1e-300;
            u = out.row(begin + r).transpose();
            if (nonneg) {
                detail::nnls(ridged, b, u);
            } else {
                ldlt.compute(ridged);
                u = ldlt.solve(b);
            }
            out.row(begin + r) = u.transpose();
            acc.objective += std::max(0.0, side.xx[begin + r] - 2.0 * u.dot(b) + u.dot(a * u));
            acc.k += (u * u.transpose()).cwiseProduct(g);
            for (int c = 0; c < channels; ++c) acc.r[c] += u.cwiseProduct(rhs[c].row(r).transpose());
        }
    });
    ColourSums total{Eigen::MatrixXd::Zero(k, k), std::vector<Vec>(channels, Vec::Zero(k)), 0.0};
    for (const ColourSums& a : sums) {
        total.k += a.k;
        for (int c = 0; c < channels; ++c) total.r[c] += a.r[c];
        total.objective += a.objective;
    }
    return total;
}

// A table's valid bins in one layout and transform space: the values y (rows × columns, 0 where
// invalid) and the two Sides.
struct Data {
    std::vector<Mat> y;
    Side rows, cols;
    std::size_t valid = 0;
};

// Rewrites U·Vᵀ as its SVD (U' = Q_u A √Σ, V' = Q_v B √Σ): orthogonal columns, so float32 storage
// of the factors loses no more than float32 storage of the table would.
void canonical_svd(Solved& r) {
    const Eigen::Index k = r.u.cols();
    const Eigen::HouseholderQR<Eigen::MatrixXd> qu(r.u), qv(r.v);
    const Eigen::MatrixXd ru = qu.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd rv = qv.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    const Eigen::JacobiSVD<Eigen::MatrixXd> core(ru * rv.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd root = core.singularValues().cwiseSqrt();
    r.u = qu.householderQ() * Eigen::MatrixXd::Identity(r.u.rows(), k) * core.matrixU() * root.asDiagonal();
    r.v = qv.householderQ() * Eigen::MatrixXd::Identity(r.v.rows(), k) * core.matrixV() * root.asDiagonal();
}

// The rank-k truncated SVD of m as U·Vᵀ, each side's columns scaled by √σ. From the eigenvectors of
// the Gram matrix of m's shorter side (at most a few hundred: one of θh, θd, φd or a product with
// the third), and the other side's as m's product with them / σ. Squaring m's condition number only
// blurs components far below the leading one, which this start does not need exactly; those below
// 1e-12 of it are left 0. Not BDCSVD: the Gram matrix is small, so this is quicker, and this file is
// spared the instantiation of Eigen's SVD, which is slow to compile.
void leading_components(const Mat& m, int k, Mat& u, Mat& v) {
    const bool wide = m.rows() <= m.cols();
    const Eigen::MatrixXd gram = wide ? Eigen::MatrixXd(m * m.transpose()) : Eigen::MatrixXd(m.transpose() * m);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);  // eigenvalues ascending
    const Eigen::MatrixXd near = eig.eigenvectors().rightCols(k).rowwise().reverse();
    const Vec sigma = eig.eigenvalues().tail(k).reverse().cwiseMax(0.0).cwiseSqrt();
    Eigen::MatrixXd far = wide ? Eigen::MatrixXd(m.transpose() * near) : Eigen::MatrixXd(m * near);
    for (int j = 0; j < k; ++j) far.col(j) *= sigma(j) > 1e-12 * sigma(0) ? 1.0 / sigma(j) : 0.0;
    const Vec root = sigma.cwiseSqrt();
    u = (wide ? near : far) * root.asDiagonal();
    v = (wide ? far : near) * root.asDiagonal();
}

// NNDSVD (Boutsidis & Gallopoulos 2008): each SVD component u vᵀ replaced by the larger (by norm
// product) of its positive part u₊v₊ᵀ and negated negative part u₋v₋ᵀ, a non-negative start close to
// the truncated SVD. The leading component of a non-negative matrix is one-signed already.
void nndsvd(Mat& u, Mat& v) {
    for (Eigen::Index j = 0; j < u.cols(); ++j) {
        const Vec up = u.col(j).cwiseMax(0.0), un = (-u.col(j)).cwiseMax(0.0);
        const Vec vp = v.col(j).cwiseMax(0.0), vn = (-v.col(j)).cwiseMax(0.0);
        const double mp = up.norm() * vp.norm(), mn = un.norm() * vn.norm();
        // u.col(j) and v.col(j) carry √σ each: keep the product's scale, σ·m/(|u|·|v|).
        const double scale = std::sqrt(u.col(j).norm() * v.col(j).norm());
        const bool pos = mp >= mn;
        const Vec& a = pos ? up : un;
        const Vec& b = pos ? vp : vn;
        const double m = pos ? mp : mn;
        if (!(m > 0.0)) {
            u.col(j).setZero();
            v.col(j).setZero();
            continue;
        }
        const double g = scale * std::sqrt(m / (u.col(j).norm() * v.col(j).norm()));
        u.col(j) = g * a / a.norm();
        v.col(j) = g * b / b.norm();
    }
}

// One factorisation of `channels` matrices sharing U and V (colour weights s updated when there is
// more than one channel). `step(i)` reports progress after iteration i.
Solved solve(const Data& d, int k, bool nonneg, const FactorOptions& o, const std::function<void(int)>& step) {
    const Side &rows = d.rows, &cols = d.cols;
    const int channels = static_cast<int>(d.y.size());
    const Eigen::Index nr = rows.w.rows(), nc = cols.w.rows();
    Solved r;
    r.norm = rows.xx.sum();

    // Start: the rank-k SVD of the channels' mean, invalid entries filled with their row's weighted
    // mean (zeros would pull every component towards them); nmf starts from its NNDSVD.
    Mat mean = Mat::Zero(nr, nc);
    for (int c = 0; c < channels; ++c) mean += d.y[c] / channels;
    for (Eigen::Index i = 0; i < nr; ++i) {
        const double wsum = rows.w.row(i).sum();
        const double fill = wsum > 0.0 ? mean.row(i).dot(rows.w.row(i)) / wsum : 0.0;
        for (Eigen::Index j = 0; j < nc; ++j)
            if (!(rows.w(i, j) > 0.0)) mean(i, j) = fill;
    }
    leading_components(mean, k, r.u, r.v);
    if (nonneg) nndsvd(r.u, r.v);
    r.s = Mat::Ones(channels, k);
    if (channels > 1) {  // each channel's share of the mean
        const double base = mean.cwiseProduct(rows.w).sum();
        for (int c = 0; c < channels; ++c) {
            const double ratio = base > 0.0 ? rows.wx[c].sum() / base : 1.0;
            r.s.row(c).setConstant(ratio > 0.0 ? ratio : 1.0);
        }
    }

    const double ridge = o.space == FactorSpace::Log || o.space == FactorSpace::Cbrt ? kRidge : 0.0;
    double previous = 0.0;
    for (int it = 1; it <= o.max_iterations; ++it) {
        update_side(r.u, r.v, rows, r.s, nonneg, ridge, o.threads);
        const ColourSums sums = update_side(r.v, r.u, cols, r.s, nonneg, ridge, o.threads);
        r.objective = sums.objective;
        r.iterations = it;
        if (channels > 1) {
            Eigen::MatrixXd kk = sums.k;
            kk.diagonal().array() += 1e-10 * sums.k.trace() / k + 1e-300;
            for (int c = 0; c < channels; ++c) {
                Vec s = r.s.row(c).transpose();
                if (nonneg)
                    detail::nnls(kk, sums.r[c], s);
                else
                    s = kk.ldlt().solve(sums.r[c]);
                r.s.row(c) = s.transpose();
            }
        }
        detail::balance(r, channels > 1);
        if (!std::isfinite(r.objective) || !r.u.allFinite() || !r.v.allFinite() || !r.s.allFinite())
            throw ValueError(std::string(factor_method_name(o.method)) +
                             ": the factorisation diverged (non-finite values after " + std::to_string(it) +
                             " iterations)");
        step(it);
        if (r.objective <= 1e-24 * r.norm || (it > 1 && previous - r.objective <= o.tolerance * previous)) {
            r.converged = true;
            break;
        }
        previous = r.objective;
    }
    if (!nonneg && channels == 1) canonical_svd(r);
    return r;
}

// The largest value of each channel over the bins prepare() takes (all channels finite and ≥ 0).
std::array<float, 3> data_max(const Table& table) {
    std::array<float, 3> top{0.0f, 0.0f, 0.0f};
    for (std::size_t bin = 0; bin < table.bins(); ++bin) {
        const float f[3] = {table.at(bin, 0), table.at(bin, 1), table.at(bin, 2)};
        if (!(std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2]) && f[0] >= 0 && f[1] >= 0 && f[2] >= 0))
            continue;
        for (int c = 0; c < 3; ++c) top[c] = std::max(top[c], f[c]);
    }
    return top;
}

Data prepare(const Table& table, const FactorOptions& o, int rows, int cols, const std::vector<int>& channels) {
    const GridSpec& g = table.grid();
    const int nch = static_cast<int>(channels.size());
    Data d;
    Mat w = Mat::Zero(rows, cols);
    d.y.assign(nch, Mat::Zero(rows, cols));
    for (std::size_t bin = 0; bin < table.bins(); ++bin) {
        bool ok = true;
        for (int c = 0; c < 3; ++c) {
            const float f = table.at(bin, c);
            ok = ok && std::isfinite(f) && f >= 0.0f;
        }
        if (!ok) continue;
        double weight = 1.0;
        if (o.space == FactorSpace::Cos) {
            const int ip = static_cast<int>(bin % g.n_phi_d), id = static_cast<int>(bin / g.n_phi_d % g.n_theta_d),
                      ih = static_cast<int>(bin / g.n_phi_d / g.n_theta_d);
            const double cos_i = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)}).first.z;
            weight = cos_i > 0.0 ? cos_i * cos_i : 0.0;
            // On a warped θd axis, each sample stands for dθd/du of the metric's linear θd axis.
            if (g.theta_d_warp != 0.0)
                weight *= 1.0 / (1.0 - g.theta_d_warp + g.theta_d_warp * std::numbers::pi / 2.0 * std::sin(g.theta_d_at(id)));
            // On a warped θh axis, dθh/du of the metric's square-root axis.
            if (g.theta_h_warp != 0.0) weight *= axis::theta_h_density(ih + g.sample_offset(), g.n_theta_h, g.theta_h_warp);
        }
        if (!(weight > 0.0)) continue;
        ++d.valid;
        const Eigen::Index i = static_cast<Eigen::Index>(bin / cols), j = static_cast<Eigen::Index>(bin % cols);
        w(i, j) = weight;
        for (int c = 0; c < nch; ++c) d.y[c](i, j) = detail::to_space(o.space, table.at(bin, channels[c]));
    }
    d.rows.xx = Vec::Zero(rows);
    d.cols.xx = Vec::Zero(cols);
    for (int c = 0; c < nch; ++c) {
        const Mat wx = w.cwiseProduct(d.y[c]);
        const Mat wxx = wx.cwiseProduct(d.y[c]);
        d.rows.xx += wxx.rowwise().sum();
        d.cols.xx += wxx.colwise().sum().transpose();
        d.rows.wx.push_back(wx);
        d.cols.wx.push_back(wx.transpose());
    }
    d.cols.w = w.transpose();
    d.rows.w = std::move(w);
    return d;
}

}  // namespace

Factored factor(const Table& table, const FactorOptions& o) {
    const char* method = factor_method_name(o.method);
    Factors f;
    f.grid = table.grid();
    f.method = o.method;
    f.space = o.space;
    f.layout = o.layout;
    f.colour = o.colour;
    f.rank = o.rank;
    const int rows = f.rows(), cols = f.columns();
    if (o.rank < 1 || o.rank > std::min(rows, cols))
        throw ValueError(std::string(method) + ": rank " + std::to_string(o.rank) + " outside 1.." +
                         std::to_string(std::min(rows, cols)) + " for grid " + f.grid.str() + " in layout " +
                         factor_layout_name(o.layout));
    if (o.max_iterations < 1) throw ValueError(std::string(method) + ": the iteration cap must be at least 1");
    if (o.fit != FactorFit::Samples)
        throw ValueError(std::string(method) + ": fit=lsq fits the factors to the source's values between the "
                         "table's samples; give the source too (factor(source, table, options))");
    f.dtype = o.dtype;
    const bool nonneg = o.method == FactorMethod::Nmf;
    const bool shared = o.colour == FactorColour::Shared;
    const int k = o.rank, m = f.row_width();
    const int solves = shared ? 1 : 3;
    const auto step = [&](int solve_index) {
        return [&, solve_index](int it) {
            if (o.progress) o.progress(std::min(1.0, (solve_index + static_cast<double>(it) / o.max_iterations) / solves));
        };
    };

    FactorReport report;
    double objective = 0.0, norm = 0.0;
    f.u.assign(static_cast<std::size_t>(rows) * m, 0.0f);
    f.v.assign(static_cast<std::size_t>(cols) * m, 0.0f);
    report.converged = true;
    for (int solve_index = 0; solve_index < solves; ++solve_index) {
        const std::vector<int> channels = shared ? std::vector<int>{0, 1, 2} : std::vector<int>{solve_index};
        const Data d = prepare(table, o, rows, cols, channels);
        if (d.valid == 0) throw ValueError(std::string(method) + ": the table has no valid bins to factor");
        Solved r = solve(d, k, nonneg, o, step(solve_index));
        if (o.dtype == FactorDtype::F16) detail::scale_for_f16(r, shared);  // FactoredBrdf rounds them
        report.valid_bins = d.valid;
        report.iterations = std::max(report.iterations, r.iterations);
        report.converged = report.converged && r.converged;
        objective += r.objective;
        norm += r.norm;
        const int offset = shared ? 0 : solve_index * k;  // separate: channel c's components at c·rank
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < k; ++j) f.u[static_cast<std::size_t>(i) * m + offset + j] = static_cast<float>(r.u(i, j));
        for (int i = 0; i < cols; ++i)
            for (int j = 0; j < k; ++j) f.v[static_cast<std::size_t>(i) * m + offset + j] = static_cast<float>(r.v(i, j));
        if (shared)
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < k; ++j) f.colour_weights.push_back(static_cast<float>(r.s(c, j)));
    }
    report.residual = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
    f.max_value = data_max(table);
    Factored out{std::make_unique<FactoredBrdf>(std::move(f), o.sampler), report};
    out.brdf->reconstruct(&out.report.clamped);
    return out;
}

}  // namespace brdfz
