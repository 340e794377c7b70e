#include "brdfz/repr/pca.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/parallel.h"

namespace brdfz {
namespace {

// Work is split into slices of this many bins: a slice of N tables' mapped values stays in cache.
constexpr std::size_t kSliceBins = 2048;

using MatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic>;
using ConstMapXf = Eigen::Map<const MatrixXf>;

int slice_count(std::size_t bins) { return static_cast<int>((bins + kSliceBins - 1) / kSliceBins); }

struct Slice {
    std::size_t begin, end;  // bins
    std::size_t size() const { return end - begin; }
};
Slice slice_of(int s, std::size_t bins) {
    const std::size_t begin = static_cast<std::size_t>(s) * kSliceBins;
    return {begin, std::min(bins, begin + kSliceBins)};
}

// cosθi·cosθo at each bin's sample position (φh = 0); 0 when either direction is below the horizon.
std::vector<float> bin_weights(const GridSpec& g) {
    std::vector<float> w(g.bins());
    for (int ih = 0; ih < g.n_theta_h; ++ih)
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const auto [wi, wo] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                w[g.index(ih, id, ip)] = wi.z > 0.0 && wo.z > 0.0 ? static_cast<float>(wi.z * wo.z) : 0.0f;
            }
    return w;
}

bool valid_value(float v) { return std::isfinite(v) && v >= 0.0f; }
bool valid_bin(const float* v) { return valid_value(v[0]) && valid_value(v[1]) && valid_value(v[2]); }

// The forward mapping of one value (see pca.h).
inline float map_value(float f, float median, float w, float eps) {
    return std::log((f * w + eps) / (median * w + eps));
}

// Median of the values in v (reordered), averaging the middle two of an even count.
float median_of(std::vector<float>& v) {
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    const float upper = v[mid];
    if (v.size() % 2) return upper;
    return 0.5f * (upper + *std::max_element(v.begin(), v.begin() + mid));
}

// Bases are trained and stored on the reciprocal and full φd axes only.
constexpr const char* kNoBilateral = "folds φd by the mirror (symmetry bilateral): a basis's φd axis is reciprocal or none";

}  // namespace

PcaBasis::PcaBasis(GridSpec grid, double epsilon, std::vector<float> median, std::vector<float> mean,
                   std::vector<float> components, std::vector<double> variances, Origin origin)
    : grid_(grid), epsilon_(epsilon), median_(std::move(median)), mean_(std::move(mean)),
      components_(std::move(components)), variances_(std::move(variances)), origin_(std::move(origin)) {
    grid_.validate();
    if (grid_.bilateral()) throw ValueError("PCA basis: grid " + grid_.str() + " " + kNoBilateral);
    const std::size_t d = grid_.bins() * 3;
    if (!(std::isfinite(epsilon_) && epsilon_ > 0.0))
        throw ValueError("PCA basis: epsilon " + std::to_string(epsilon_) + " is not a positive number");
    if (median_.size() != d || mean_.size() != d || components_.size() != d * variances_.size())
        throw ValueError("PCA basis: part sizes (median " + std::to_string(median_.size()) + ", mean " +
                         std::to_string(mean_.size()) + ", components " + std::to_string(components_.size()) +
                         " for " + std::to_string(variances_.size()) + ") do not fit grid " + grid_.str());
    if (variances_.empty()) throw ValueError("PCA basis: no components");
    for (double v : variances_)
        if (!(std::isfinite(v) && v >= 0.0)) throw ValueError("PCA basis: a component variance is not finite and >= 0");
    for (float v : mean_)
        if (!std::isfinite(v)) throw ValueError("PCA basis: the mean has a value that is not finite");
    for (float v : components_)
        if (!std::isfinite(v)) throw ValueError("PCA basis: a component has a value that is not finite");
    weight_ = bin_weights(grid_);
    for (std::size_t b = 0; b < grid_.bins(); ++b) {
        const float* m = &median_[3 * b];
        const bool dropped = std::isnan(m[0]) && std::isnan(m[1]) && std::isnan(m[2]);
        if (dropped) continue;
        if (!valid_bin(m)) throw ValueError("PCA basis: bin " + std::to_string(b) + " has a median that is not finite and >= 0");
        // A kept bin below the horizon could not be mapped back.
        if (!(weight_[b] > 0.0f)) throw ValueError("PCA basis: bin " + std::to_string(b) + " below the horizon is not dropped");
        ++kept_bins_;
    }
}

std::size_t PcaBasis::nbytes() const {
    return (median_.size() + mean_.size() + components_.size()) * sizeof(float) + variances_.size() * sizeof(double);
}

std::vector<float> PcaBasis::map(const Table& table) const {
    if (!(table.grid() == grid_))
        throw ValueError("PCA: a table on grid " + table.grid().str() + " does not fit the basis's grid " + grid_.str());
    const float eps = static_cast<float>(epsilon_);
    std::vector<float> y(dims(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t b = 0; b < grid_.bins(); ++b) {
        const float* f = table.data() + 3 * b;
        const float* m = &median_[3 * b];
        if (std::isnan(m[0]) || !valid_bin(f)) continue;
        for (int c = 0; c < 3; ++c) y[3 * b + c] = map_value(f[c], m[c], weight_[b], eps);
    }
    return y;
}

std::vector<float> PcaBasis::project(const Table& table, int k) const {
    if (k < 0 || k > k_max())
        throw ValueError("PCA: k = " + std::to_string(k) + " outside 0.." + std::to_string(k_max()) +
                         " (the basis's components)");
    const std::vector<float> y = map(table);
    if (k == 0) return {};
    const ConstMapXf basis(components_.data(), static_cast<Eigen::Index>(dims()), k_max());
    // Normal equations over the table's valid bins: (BᵀB) c = Bᵀ(y − mean), restricted to those rows.
    const int slices = slice_count(grid_.bins());
    const int workers = std::min(resolve_threads(0), slices);
    std::vector<Eigen::MatrixXd> gram(workers, Eigen::MatrixXd::Zero(k, k));
    std::vector<Eigen::VectorXd> rhs(workers, Eigen::VectorXd::Zero(k));
    std::vector<std::size_t> used(workers, 0);
    detail::parallel_for(slices, workers, [&](int w, int s) {
        const Slice sl = slice_of(s, grid_.bins());
        const Eigen::Index r0 = static_cast<Eigen::Index>(3 * sl.begin), rows = static_cast<Eigen::Index>(3 * sl.size());
        MatrixXf b = basis.block(r0, 0, rows, k);
        Eigen::VectorXf r(rows);
        for (Eigen::Index i = 0; i < rows; ++i) {
            const float v = y[r0 + i];
            const bool ok = !std::isnan(v);
            r[i] = ok ? v - mean_[r0 + i] : 0.0f;
            if (!ok) b.row(i).setZero();
            used[w] += ok;
        }
        gram[w] += (b.transpose() * b).cast<double>();
        rhs[w] += (b.transpose() * r).cast<double>();
    });
    for (int w = 1; w < workers; ++w) {
        gram[0] += gram[w];
        rhs[0] += rhs[w];
        used[0] += used[w];
    }
    if (used[0] < static_cast<std::size_t>(k))
        throw ValueError("PCA: the table has " + std::to_string(used[0] / 3) + " valid bins where the basis has values, "
                         "too few for " + std::to_string(k) + " coefficients");
    // Robust Cholesky; a pivot that vanishes against the largest means the valid bins leave some
    // combination of components undetermined.
    const Eigen::LDLT<Eigen::MatrixXd> solver(gram[0]);
    const Eigen::VectorXd pivots = solver.vectorD();
    const Eigen::VectorXd c = solver.solve(rhs[0]);
    if (solver.info() != Eigen::Success || !c.allFinite() || !(pivots.minCoeff() > 1e-10 * pivots.maxCoeff()))
        throw ValueError("PCA: the table's valid bins do not determine " + std::to_string(k) + " coefficients");
    std::vector<float> out(k);
    for (int j = 0; j < k; ++j) out[j] = static_cast<float>(c[j]);
    return out;
}

std::vector<float> PcaBasis::combine(std::span<const float> coefficients) const {
    const int k = static_cast<int>(coefficients.size());
    if (k > k_max())
        throw ValueError("PCA: " + std::to_string(k) + " coefficients for a basis of " + std::to_string(k_max()) + " components");
    std::vector<float> y(mean_);
    if (k == 0) return y;
    const ConstMapXf basis(components_.data(), static_cast<Eigen::Index>(dims()), k_max());
    const Eigen::Map<const Eigen::VectorXf> c(coefficients.data(), k);
    Eigen::Map<Eigen::VectorXf>(y.data(), static_cast<Eigen::Index>(y.size())) += basis.leftCols(k) * c;
    return y;
}

Table PcaBasis::reconstruct(std::span<const float> coefficients, ValidityCounts* counts) const {
    const std::vector<float> y = combine(coefficients);
    const double eps = epsilon_;
    Table table(grid_);
    ValidityCounts n;
    for (std::size_t b = 0; b < grid_.bins(); ++b) {
        const float* m = &median_[3 * b];
        if (std::isnan(m[0])) continue;
        const double w = weight_[b];
        Rgb f;
        bool clamped = false, finite = true;
        for (int c = 0; c < 3; ++c) {
            // Inverse of map_value; in double so that (… − ε)/w keeps its digits at grazing angles.
            const double v = (std::exp(static_cast<double>(y[3 * b + c])) * (m[c] * w + eps) - eps) / w;
            finite = finite && std::isfinite(static_cast<float>(v));
            clamped = clamped || v < 0.0;
            f[c] = std::max(v, 0.0);
        }
        if (!finite) {
            ++n.inf;  // a coefficient vector far outside the training set; the bin is left invalid
            continue;
        }
        n.clamped += clamped;
        ++n.valid;
        table.set(b, f);
    }
    if (counts) *counts = n;
    return table;
}

PcaBasis train_pca_basis(std::span<const Table* const> tables, const PcaTrainOptions& options, PcaTrainReport* report) {
    const std::size_t n = tables.size();
    if (n < 2) throw ValueError("PCA training needs at least 2 tables, got " + std::to_string(n));
    if (options.k_max < 1) throw ValueError("PCA training: k_max must be at least 1");
    if (!(std::isfinite(options.epsilon) && options.epsilon > 0.0))
        throw ValueError("PCA training: epsilon must be a positive number");
    if (!(options.max_invalid_fraction >= 0.0 && options.max_invalid_fraction < 1.0))
        throw ValueError("PCA training: max_invalid_fraction must be in [0, 1)");
    const GridSpec grid = tables[0]->grid();
    for (std::size_t t = 1; t < n; ++t)
        if (!(tables[t]->grid() == grid))
            throw ValueError("PCA training: table " + std::to_string(t + 1) + " is on grid " + tables[t]->grid().str() +
                             ", table 1 on " + grid.str() + " (all must share one grid)");
    if (grid.bilateral()) throw ValueError("PCA training: grid " + grid.str() + " " + kNoBilateral);
    const std::size_t bins = grid.bins(), d = 3 * bins;
    const std::vector<float> weight = bin_weights(grid);
    const float eps = static_cast<float>(options.epsilon);
    const int slices = slice_count(bins);
    const int workers = std::min(resolve_threads(options.threads), slices);
    const auto nan = std::numeric_limits<float>::quiet_NaN();

    std::mutex progress_mutex;
    double done = 0;
    const auto step = [&](double amount) {
        if (!options.progress) return;
        std::lock_guard lock(progress_mutex);
        done += amount;
        options.progress(std::min(done, 1.0));
    };
    // Share of the work in each pass: medians, Gram matrix, components.
    const double kPass[3] = {0.2, 0.4, 0.4};

    // Pass 1: which bins are kept, and their medians.
    std::vector<float> median(d, nan);
    std::vector<std::size_t> imputed(workers, 0);
    const std::size_t max_invalid = static_cast<std::size_t>(std::floor(options.max_invalid_fraction * n));
    detail::parallel_for(slices, workers, [&](int w, int s) {
        const Slice sl = slice_of(s, bins);
        std::vector<float> values[3];
        for (std::size_t b = sl.begin; b < sl.end; ++b) {
            if (!(weight[b] > 0.0f)) continue;
            for (auto& v : values) v.clear();
            for (const Table* t : tables) {
                const float* f = t->data() + 3 * b;
                if (!valid_bin(f)) continue;
                for (int c = 0; c < 3; ++c) values[c].push_back(f[c]);
            }
            const std::size_t missing = n - values[0].size();
            if (missing > max_invalid || values[0].empty()) continue;
            imputed[w] += 3 * missing;
            for (int c = 0; c < 3; ++c) median[3 * b + c] = median_of(values[c]);
        }
        step(kPass[0] / slices);
    });

    // The N × (slice·3) block of mapped values, imputed with the median (0) where a table has none
    // and 0 in dropped bins, so that dropped bins add nothing to the Gram matrix or the mean.
    const auto mapped = [&](const Slice& sl, MatrixXf& x) {
        x.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(3 * sl.size()));
        for (std::size_t b = sl.begin; b < sl.end; ++b) {
            const Eigen::Index col = static_cast<Eigen::Index>(3 * (b - sl.begin));
            const float* m = &median[3 * b];
            for (std::size_t t = 0; t < n; ++t) {
                const float* f = tables[t]->data() + 3 * b;
                const bool ok = !std::isnan(m[0]) && valid_bin(f);
                for (int c = 0; c < 3; ++c) x(t, col + c) = ok ? map_value(f[c], m[c], weight[b], eps) : 0.0f;
            }
        }
    };

    // Pass 2: the mean, and the Gram matrix of the centred tables (N × N, accumulated in double).
    std::vector<float> mean(d, 0.0f);
    std::vector<Eigen::MatrixXd> gram(workers, Eigen::MatrixXd::Zero(n, n));
    detail::parallel_for(slices, workers, [&](int w, int s) {
        const Slice sl = slice_of(s, bins);
        MatrixXf x;
        mapped(sl, x);
        const Eigen::RowVectorXf mu = x.colwise().mean();
        x.rowwise() -= mu;
        std::copy(mu.data(), mu.data() + mu.size(), mean.begin() + 3 * sl.begin);
        // In double: the components divide by √λ, so the Gram matrix's rounding would otherwise show
        // in the weaker components' orthonormality (5e-4 in float on a small test set).
        const Eigen::MatrixXd xd = x.cast<double>();
        gram[w].selfadjointView<Eigen::Lower>().rankUpdate(xd);
        step(kPass[1] / slices);
    });
    for (int w = 1; w < workers; ++w) gram[0] += gram[w];

    // Eigenvectors u of the Gram matrix give the components Xcᵀu/√λ (Turk & Pentland's trick): unit
    // vectors in bins·3 dimensions from an N × N problem. Eigenvalues come in ascending order.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram[0]);
    if (eig.info() != Eigen::Success) throw ValueError("PCA training: the eigen-decomposition did not converge");
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const double top = std::max(lambda[static_cast<Eigen::Index>(n) - 1], 0.0);
    // Directions with no variance (fewer distinct tables than k_max) are not components.
    int k = 0;
    while (k < options.k_max && k < static_cast<int>(n) - 1 &&
           lambda[static_cast<Eigen::Index>(n) - 1 - k] > 1e-10 * top && top > 0.0)
        ++k;
    if (k == 0) throw ValueError("PCA training: the " + std::to_string(n) + " tables do not differ in their kept bins");
    Eigen::MatrixXd scaled(static_cast<Eigen::Index>(n), k);
    std::vector<double> variances(k);
    for (int j = 0; j < k; ++j) {
        const Eigen::Index col = static_cast<Eigen::Index>(n) - 1 - j;
        scaled.col(j) = eig.eigenvectors().col(col) / std::sqrt(lambda[col]);
        variances[j] = lambda[col] / static_cast<double>(n - 1);
    }

    // Pass 3: the components, slice by slice.
    std::vector<float> components(static_cast<std::size_t>(k) * d);
    detail::parallel_for(slices, workers, [&](int, int s) {
        const Slice sl = slice_of(s, bins);
        MatrixXf x;
        mapped(sl, x);
        const Eigen::Map<const Eigen::RowVectorXf> mu(mean.data() + 3 * sl.begin, x.cols());
        x.rowwise() -= mu;
        const Eigen::MatrixXd c = scaled.transpose() * x.cast<double>();  // k × (slice·3)
        for (int j = 0; j < k; ++j)
            for (Eigen::Index i = 0; i < c.cols(); ++i) components[j * d + 3 * sl.begin + i] = static_cast<float>(c(j, i));
        step(kPass[2] / slices);
    });

    if (report) {
        PcaTrainReport r;
        r.tables = n;
        for (std::size_t b = 0; b < bins; ++b) (std::isnan(median[3 * b]) ? r.dropped_bins : r.kept_bins)++;
        for (std::size_t v : imputed) r.imputed_values += v;
        r.total_variance = gram[0].trace() / static_cast<double>(n - 1);
        r.variances = variances;
        *report = std::move(r);
    }
    return PcaBasis(grid, options.epsilon, std::move(median), std::move(mean), std::move(components), std::move(variances));
}

namespace {
std::vector<float> checked_coefficients(const PcaBasis& basis, std::vector<float> c) {
    if (c.size() > static_cast<std::size_t>(basis.k_max()))
        throw ValueError("PCA: " + std::to_string(c.size()) + " coefficients for a basis of " +
                         std::to_string(basis.k_max()) + " components");
    for (float v : c)
        if (!std::isfinite(v)) throw ValueError("PCA: a coefficient is not finite");
    return c;
}
}  // namespace

PcaBrdf::PcaBrdf(std::shared_ptr<const PcaBasis> basis, std::vector<float> coefficients, Lookup lookup,
                 BasisStorage storage, SamplerKind sampler)
    : basis_(basis ? std::move(basis) : throw ValueError("PCA: no basis given")),
      coefficients_(checked_coefficients(*basis_, std::move(coefficients))),
      storage_(storage),
      table_(basis_->reconstruct(coefficients_, &counts_), lookup, sampler) {}

PcaBrdf::PcaBrdf(std::shared_ptr<const PcaBasis> basis, std::vector<float> coefficients, Lookup lookup,
                 BasisStorage storage, CompactSampler sampler)
    : basis_(basis ? std::move(basis) : throw ValueError("PCA: no basis given")),
      coefficients_(checked_coefficients(*basis_, std::move(coefficients))),
      storage_(storage),
      table_(basis_->reconstruct(coefficients_, &counts_), lookup, std::move(sampler)) {}

std::string PcaBrdf::describe() const {
    const PcaBasis& b = *basis_;
    std::string s = "pca k=" + std::to_string(k()) + " of a " + std::to_string(b.k_max()) + "-component basis on " +
                    b.grid().str() + (b.grid().reciprocal() ? "" : ", symmetry none") + " (basis ";
    s += storage_ == BasisStorage::Embedded ? "embedded" : "referenced";
    if (!b.origin().sha256.empty()) s += ", sha256 " + b.origin().sha256.substr(0, 12);
    return s + "), " + lookup_name(table_.lookup()) + " lookup";
}

Rgb PcaBrdf::eval_above(const Vec3& wi, const Vec3& wo) const { return table_.eval(wi, wo); }

void PcaBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    table_.eval(std::span<const Vec3>(wi, n), std::span<const Vec3>(wo, n), std::span<Rgb>(out, n));
}

BrdfSample PcaBrdf::sample_above(const Vec3& wo, double u1, double u2) const { return table_.sample(wo, u1, u2); }

// The table's batch kernel, not the default one draw at a time: its passes run across draws.
void PcaBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    table_.sample(std::span<const Vec3>(wo, n), std::span<const std::array<double, 2>>(u, n), std::span<BrdfSample>(out, n));
}

double PcaBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return table_.pdf(wo, wi); }

}  // namespace brdfz
