// PCA across materials (Matusik et al. 2003; Nielsen et al. 2015): a basis learnt once from a set of
// tables on one Rusinkiewicz grid; a material is then k coefficients plus a reference to the basis.
//
// The mapped space (after Nielsen et al. 2015, "On optimal, minimal BRDF sampling"): per bin and channel
//   y = ln((f·w + ε) / (m·w + ε)),   w = cosθi·cosθo at the bin's sample position (φh = 0),
// where m is the median of the training materials' valid values in that bin and channel. The cosine
// weight makes grazing bins, which matter little in renderings and are noisiest in measurements, count
// less; the log evens out the dynamic range between diffuse and specular bins; dividing by the median
// centres each bin so that the components describe how materials differ, not the average shape.
// One vector per material holds all three channels (bins·3 values, RGB interleaved as in Table), so
// a component captures colour together with shape: k coefficients describe the whole material.
//
// Invalid data: a bin invalid (Table::valid) in more than max_invalid_fraction of the training tables,
// or whose sample position lies below the horizon, is dropped from the basis (its median is NaN, its
// mean and components 0; reconstructions leave it invalid). A kept bin missing in a training table is
// imputed with the median (mapped value 0) and counted. Projection of a material is least squares over
// ITS valid bins among the kept ones, so unmeasured bins of a new material do not pull it towards 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/table.h"

namespace brdfz {

class PcaBasis {
public:
    // Where a basis was read from, for materials that reference it (set by the container reader).
    struct Origin {
        std::string path;    // the file it was read from
        std::string sha256;  // its content hash (formats/SPEC.md, "pca"), 64 hex digits
    };

    // The stored parts: per-bin-and-channel median (NaN for dropped bins), mean in the mapped space,
    // components [k][bins·3] (component-major), the variance each component explains. ValueError
    // unless the sizes agree with the grid, epsilon > 0 and every value but the medians' NaNs is
    // finite (a reader turns that into FormatError).
    PcaBasis(GridSpec grid, double epsilon, std::vector<float> median, std::vector<float> mean,
             std::vector<float> components, std::vector<double> variances, Origin origin = {});

    const GridSpec& grid() const { return grid_; }
    double epsilon() const { return epsilon_; }
    int k_max() const { return static_cast<int>(variances_.size()); }
    std::size_t dims() const { return mean_.size(); }  // bins·3
    std::span<const float> median() const { return median_; }
    std::span<const float> mean() const { return mean_; }
    std::span<const float> components() const { return components_; }  // [k_max][dims]
    std::span<const double> variances() const { return variances_; }
    std::size_t kept_bins() const { return kept_bins_; }
    const Origin& origin() const { return origin_; }
    void set_origin(Origin origin) { origin_ = std::move(origin); }

    // Bytes of the stored parameters (median, mean, components as float32; variances as float64).
    std::size_t nbytes() const;
    // cosθi·cosθo at each bin's sample position (φh = 0), 0 below the horizon: the mapping's weight w.
    std::span<const float> weights() const { return weight_; }

    // Least-squares coefficients of `table` (on grid()) over its valid, kept bins, for the first k
    // components. ValueError for another grid, k outside [0, k_max], or fewer valid bins than k.
    std::vector<float> project(const Table& table, int k) const;
    // The mapped-space vector (dims()) of a table on grid(): NaN where the table or the basis has no value.
    std::vector<float> map(const Table& table) const;
    // mean + Σ c_j·component_j in the mapped space (dims() values; dropped bins 0).
    std::vector<float> combine(std::span<const float> coefficients) const;
    // The table of a coefficient vector: the inverse mapping of combine(). Values the inverse maps
    // below 0 are set to 0 and counted in counts.clamped; dropped bins stay invalid.
    Table reconstruct(std::span<const float> coefficients, ValidityCounts* counts = nullptr) const;

private:
    GridSpec grid_;
    double epsilon_;
    std::vector<float> median_, mean_, components_;
    std::vector<double> variances_;
    std::vector<float> weight_;  // cosθi·cosθo per bin (derived from the grid, not stored)
    std::size_t kept_bins_ = 0;
    Origin origin_;
};

struct PcaTrainOptions {
    int k_max = 32;  // components kept; at most (tables − 1) are meaningful, so more are not kept
    // ε of the mapping, in 1/sr. 0.01 rather than Nielsen et al.'s 0.001: held-out materials reconstruct
    // with a lower cos_rmse_rel at k = 32 (bench/pca measures it).
    double epsilon = 0.01;
    double max_invalid_fraction = 0.25;  // a bin invalid in more of the tables is dropped
    int threads = 0;                     // 0: one per hardware thread
    std::function<void(double)> progress;  // fraction done (0..1], from worker threads under a lock
};

struct PcaTrainReport {
    std::size_t tables = 0;
    std::size_t kept_bins = 0, dropped_bins = 0;
    std::size_t imputed_values = 0;  // kept-bin values missing in a training table, set to the median
    double total_variance = 0;       // of the centred training set in the mapped space
    std::vector<double> variances;   // of the kept components, descending
};

// Learns a basis from tables on one grid (ValueError: fewer than 2 tables, grids differing, k_max < 1).
// Memory: beside the tables, the basis itself and a slice of work per thread (the N×N Gram matrix of
// the centred tables gives the components, so no bins×N matrix is formed).
PcaBasis train_pca_basis(std::span<const Table* const> tables, const PcaTrainOptions& options = {},
                         PcaTrainReport* report = nullptr);

// A material as k coefficients of a shared basis. The table they describe is reconstructed once, at
// construction (a cache, not stored), so evaluation and sampling are those of a TabularBrdf.
class PcaBrdf final : public Brdf {
public:
    // How a container stores the basis beside the coefficients (formats/SPEC.md, "pca").
    enum class BasisStorage {
        Referenced,  // by file name and content hash; needs a basis read from a file (origin())
        Embedded,    // the basis's datasets in the material's own file
    };

    // ValueError when there are more coefficients than the basis has components, or one is not finite.
    // The reconstruction's sampler is built of that kind, or is the stored one given.
    PcaBrdf(std::shared_ptr<const PcaBasis> basis, std::vector<float> coefficients, Lookup lookup = Lookup::Linear,
            BasisStorage storage = BasisStorage::Referenced, SamplerKind sampler = SamplerKind::Compact);
    PcaBrdf(std::shared_ptr<const PcaBasis> basis, std::vector<float> coefficients, Lookup lookup,
            BasisStorage storage, CompactSampler sampler);

    const PcaBasis& basis() const { return *basis_; }
    const std::shared_ptr<const PcaBasis>& shared_basis() const { return basis_; }
    std::span<const float> coefficients() const { return coefficients_; }
    int k() const { return static_cast<int>(coefficients_.size()); }
    BasisStorage basis_storage() const { return storage_; }
    const TabularBrdf& table() const { return table_; }
    // Of the reconstruction: negative values set to 0 (clamped), valid bins.
    const ValidityCounts& counts() const { return counts_; }

    int channels() const override { return 3; }
    // The per-material part only: k float32 coefficients and the 32-byte SHA-256 naming the basis.
    // The basis is shared and reports its own size (PcaBasis::nbytes).
    std::size_t nbytes() const override { return coefficients_.size() * sizeof(float) + kBasisRefBytes; }
    std::string describe() const override;
    bool reciprocal() const override { return table_.reciprocal(); }
    const GridSpec* grid() const override { return &basis_->grid(); }

    static constexpr std::size_t kBasisRefBytes = 32;

protected:
    BRDFZ_BRDF_KERNELS;

private:
    std::shared_ptr<const PcaBasis> basis_;
    std::vector<float> coefficients_;
    BasisStorage storage_;
    ValidityCounts counts_;
    TabularBrdf table_;
};

}  // namespace brdfz
