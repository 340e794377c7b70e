#include "brdfz/metrics.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/table.h"
#include "detail/grid_sweep.h"
#include "detail/random.h"

namespace brdfz {
namespace {

struct Sums {
    double sq[3] = {}, ref_sq[3] = {}, log_sq[3] = {}, cbrt_sq[3] = {};
    std::size_t n = 0, negatives = 0;
};

PerChannel per_channel(const double v[3]) { return {v[0], v[1], v[2], (v[0] + v[1] + v[2]) / 3.0}; }

// One sample: reference and approximation f_r at a pair with cosθi = cos_i. A reflectance is never
// negative: values below 0 are measurement noise (RGL's vch_golden_yellow has them in 18 % of its blue
// bins), which no valid representation can follow, so every metric takes them as 0 (and counts them).
void add_sample(Sums& s, const Rgb& ref, const Rgb& app, double cos_i) {
    ++s.n;
    for (int c = 0; c < 3; ++c) {
        s.negatives += (ref[c] < 0.0) + (app[c] < 0.0);
        const double x = std::fmax(ref[c], 0.0) * cos_i, y = std::fmax(app[c], 0.0) * cos_i;
        s.sq[c] += (x - y) * (x - y);
        s.ref_sq[c] += x * x;
        const double dl = std::log1p(x) - std::log1p(y);
        s.log_sq[c] += dl * dl;
        const double dc = std::cbrt(x) - std::cbrt(y);
        s.cbrt_sq[c] += dc * dc;
    }
}

Metrics to_metrics(const Sums& total) {
    if (total.n == 0) throw ValueError("metrics: no valid reference bin inside the angular cut-off");
    if (total.ref_sq[0] == 0.0 && total.ref_sq[1] == 0.0 && total.ref_sq[2] == 0.0)
        throw ValueError("metrics: the reference is zero or negative at every sample inside the angular cut-off: "
                         "there is no reflectance to measure errors against");
    double cos_rmse[3], rel[3], log_rmse[3], cbrt_rmse[3];
    for (int c = 0; c < 3; ++c) {
        cos_rmse[c] = std::sqrt(total.sq[c] / total.n);
        // An all-zero reference has no scale: relative error is 0 if the approximation is too, else inf.
        rel[c] = total.ref_sq[c] > 0.0 ? std::sqrt(total.sq[c] / total.ref_sq[c])
                                       : (total.sq[c] > 0.0 ? INFINITY : 0.0);
        log_rmse[c] = std::sqrt(total.log_sq[c] / total.n);
        cbrt_rmse[c] = std::sqrt(total.cbrt_sq[c] / total.n);
    }
    Metrics m;
    m.cos_rmse = per_channel(cos_rmse);
    m.cos_rmse_rel = per_channel(rel);
    m.log_rmse = per_channel(log_rmse);
    m.cbrt_rmse = per_channel(cbrt_rmse);
    m.samples = total.n;
    m.negatives = total.negatives;
    return m;
}

double min_cos_of(const MetricOptions& options) {
    if (!(options.max_theta_deg > 0.0 && options.max_theta_deg <= 90.0))
        throw ValueError("metrics: max_theta_deg must be in (0, 90]");
    return std::cos(options.max_theta_deg * std::numbers::pi / 180.0);
}

void merge(Sums& total, const Sums& s) {
    total.n += s.n;
    total.negatives += s.negatives;
    for (int c = 0; c < 3; ++c) {
        total.sq[c] += s.sq[c];
        total.ref_sq[c] += s.ref_sq[c];
        total.log_sq[c] += s.log_sq[c];
        total.cbrt_sq[c] += s.cbrt_sq[c];
    }
}

bool finite(const Rgb& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// The grid the metrics are taken on over Over::Grid, validated.
GridSpec metric_grid(const Brdf& reference, const MetricOptions& options) {
    const Table* ref_table = reference.stored_table();
    const GridSpec g = ref_table ? ref_table->grid() : options.grid;
    g.validate();
    return g;
}

// The grid's samples, one θh slice ih at a time: slice(worker, ih, wi, wo) on the slice's pairs first
// (callers evaluate an approximation there in one batch), then keep(worker, ih, k, wi, wo, ref) for
// each bin k of the slice that is kept, ref being the reference's value there.
template <typename Slice, typename Keep>
void visit_grid(const Brdf& reference, const MetricOptions& options, int workers, Slice&& slice, Keep&& keep) {
    // Extrapolated reference values (beyond its measured range) are no measure of error.
    const double theta_max = reference.measured_theta_max();
    const double min_cos = theta_max < std::numbers::pi / 2 ? std::max(min_cos_of(options), std::cos(theta_max))
                                                            : min_cos_of(options);
    const Table* ref_table = reference.stored_table();
    const GridSpec g = metric_grid(reference, options);
    std::vector<std::vector<Rgb>> ref_f(workers);
    detail::sweep_slices(g, workers, [&](int w, int ih, std::span<const Vec3> wi, std::span<const Vec3> wo) {
        slice(w, ih, wi, wo);
        ref_f[w].resize(wi.size());
        if (!ref_table) reference.eval(wi, wo, ref_f[w]);
        const std::size_t base = g.index(ih, 0, 0);
        for (std::size_t k = 0; k < wi.size(); ++k) {
            if (!(wi[k].z > min_cos && wo[k].z > min_cos)) continue;
            Rgb ref = ref_f[w][k];
            if (ref_table) {
                if (!ref_table->valid(base + k)) continue;
                for (int c = 0; c < 3; ++c) ref[c] = ref_table->at(base + k, c);
            }
            if (!finite(ref)) continue;  // a reference without a value at this bin is not a sample
            keep(w, ih, k, wi[k], wo[k], ref);
        }
    });
}

// Over directions: the elevation cut-offs (radians) of wi and wo.
std::pair<double, double> direction_cutoffs(const Brdf& reference, const MetricOptions& options) {
    min_cos_of(options);  // checks max_theta_deg
    if (options.directions < 1 || options.directions > MetricOptions::kMaxDirections)
        throw ValueError("metrics: the number of direction pairs must be in [1, 2^30]");
    const double theta_o = options.max_theta_deg * std::numbers::pi / 180.0;
    const double measured = reference.measured_theta_max();
    if (!(measured > 0.0)) throw ValueError("metrics: the reference has no measured range of incident elevations");
    return {std::min(theta_o, measured), theta_o};
}

// Pairs per block over directions: drawn, evaluated and summed together, blocks summed in order.
constexpr std::size_t kDirectionBlock = 4096;

}  // namespace

Over parse_over(const std::string& name) {
    if (name == "grid") return Over::Grid;
    if (name == "directions") return Over::Directions;
    throw ValueError("metrics: unknown domain '" + name + "' (grid or directions)");
}

const char* over_name(Over over) { return over == Over::Grid ? "grid" : "directions"; }

void direction_pairs(std::uint64_t first, std::uint64_t seed, double theta_i_max, double theta_o_max,
                     std::span<Vec3> wi, std::span<Vec3> wo) {
    if (wi.size() != wo.size()) throw ValueError("direction_pairs: wi and wo differ in length");
    for (double t : {theta_i_max, theta_o_max})
        if (!(t > 0.0 && t <= std::numbers::pi / 2)) throw ValueError("direction_pairs: a cut-off outside (0, pi/2]");
    // Uniform in solid angle over a cap θ < θmax: cosθ uniform in (cos θmax, 1], φ uniform.
    const double span_i = 1.0 - std::cos(theta_i_max), span_o = 1.0 - std::cos(theta_o_max);
    const auto direction = [](double u, double v, double span) {
        const double z = 1.0 - u * span;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2.0 * std::numbers::pi * v;
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    for (std::size_t j = 0; j < wi.size(); ++j) {
        const std::uint64_t k = 4 * (first + j);
        wi[j] = direction(detail::unit_hash(k, seed), detail::unit_hash(k + 1, seed), span_i);
        wo[j] = direction(detail::unit_hash(k + 2, seed), detail::unit_hash(k + 3, seed), span_o);
    }
}

Metrics compare(const Brdf& reference, const Brdf& approx, const MetricOptions& options) {
    const int workers = resolve_threads(options.threads);
    if (options.over == Over::Directions) {
        // Named copies: clang before 16 cannot capture structured bindings in the lambda below.
        const std::pair<double, double> cutoffs = direction_cutoffs(reference, options);
        const double theta_i = cutoffs.first, theta_o = cutoffs.second;
        const std::size_t n = options.directions, blocks = (n + kDirectionBlock - 1) / kDirectionBlock;
        std::vector<Sums> sums(blocks);
        struct Buffers {
            std::vector<Vec3> wi, wo;
            std::vector<Rgb> ref, app;
        };
        std::vector<Buffers> buf(workers);
        detail::parallel_for(static_cast<int>(blocks), workers, [&](int w, int b) {
            const std::size_t first = static_cast<std::size_t>(b) * kDirectionBlock;
            const std::size_t m = std::min(kDirectionBlock, n - first);
            Buffers& x = buf[w];
            x.wi.resize(m), x.wo.resize(m), x.ref.resize(m), x.app.resize(m);
            direction_pairs(first, options.seed, theta_i, theta_o, x.wi, x.wo);
            reference.eval(x.wi, x.wo, x.ref);
            approx.eval(x.wi, x.wo, x.app);
            for (std::size_t k = 0; k < m; ++k)
                if (finite(x.ref[k]) && finite(x.app[k])) add_sample(sums[b], x.ref[k], x.app[k], x.wi[k].z);
        });
        Sums total;
        for (const Sums& s : sums) merge(total, s);
        return to_metrics(total);
    }

    // Sums per θh slice, added in order: the result does not depend on the thread count.
    const GridSpec g = metric_grid(reference, options);
    std::vector<Sums> sums(static_cast<std::size_t>(g.n_theta_h));
    // An approximation storing a table on the reference's grid is read at the bins as the reference
    // is, its stored values: a table against itself is exactly 0, whatever either's lookup.
    const Table* ref_table = reference.stored_table();
    const Table* app_table = approx.stored_table();
    const bool same_bins = ref_table && app_table && app_table->grid() == ref_table->grid();
    std::vector<std::vector<Rgb>> app_f(workers);
    visit_grid(
        reference, options, workers,
        [&](int w, int, std::span<const Vec3> wi, std::span<const Vec3> wo) {
            app_f[w].resize(wi.size());
            approx.eval(wi, wo, app_f[w]);
        },
        [&](int w, int ih, std::size_t k, const Vec3& wi, const Vec3&, const Rgb& ref) {
            Rgb app = app_f[w][k];
            const std::size_t bin = g.index(ih, 0, 0) + k;
            if (same_bins && app_table->valid(bin))
                for (int c = 0; c < 3; ++c) app[c] = app_table->at(bin, c);
            if (finite(app)) add_sample(sums[static_cast<std::size_t>(ih)], ref, app, wi.z);
        });
    Sums total;
    for (const Sums& s : sums) merge(total, s);
    return to_metrics(total);
}

MetricSamples metric_samples(const Brdf& reference, const MetricOptions& options) {
    MetricSamples out;
    if (options.over == Over::Directions) {
        const auto [theta_i, theta_o] = direction_cutoffs(reference, options);
        out.wi.resize(options.directions), out.wo.resize(options.directions), out.reference.resize(options.directions);
        direction_pairs(0, options.seed, theta_i, theta_o, out.wi, out.wo);
        reference.eval(out.wi, out.wo, out.reference);
        return out;
    }
    // The kept bins of each θh slice, concatenated in slice order.
    std::vector<MetricSamples> slices(static_cast<std::size_t>(metric_grid(reference, options).n_theta_h));
    visit_grid(
        reference, options, resolve_threads(options.threads), [](int, int, auto, auto) {},
        [&](int, int ih, std::size_t, const Vec3& wi, const Vec3& wo, const Rgb& ref) {
            MetricSamples& s = slices[static_cast<std::size_t>(ih)];
            s.wi.push_back(wi), s.wo.push_back(wo), s.reference.push_back(ref);
        });
    for (const MetricSamples& s : slices) {
        out.wi.insert(out.wi.end(), s.wi.begin(), s.wi.end());
        out.wo.insert(out.wo.end(), s.wo.begin(), s.wo.end());
        out.reference.insert(out.reference.end(), s.reference.begin(), s.reference.end());
    }
    return out;
}

Metrics reciprocity_error(const Brdf& brdf, const MetricOptions& options) {
    // The same BRDF read the other way round.
    class Exchanged final : public Brdf {
    public:
        explicit Exchanged(const Brdf& b) : b_(b) {}
        int channels() const override { return b_.channels(); }
        std::size_t nbytes() const override { return b_.nbytes(); }
        std::string describe() const override { return b_.describe(); }
        double measured_theta_max() const override { return b_.measured_theta_max(); }

    protected:
        Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wo, wi); }
        void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override {
            b_.eval(std::span(wo, n), std::span(wi, n), std::span(out, n));
        }

    private:
        const Brdf& b_;
    };
    MetricOptions o = options;
    o.over = Over::Directions;
    // Both directions are incident on one side: both within the measured range.
    o.max_theta_deg = std::min(options.max_theta_deg, brdf.measured_theta_max() * 180.0 / std::numbers::pi);
    return compare(brdf, Exchanged(brdf), o);
}

Metrics compare_values(std::span<const Vec3> wi, std::span<const Rgb> reference, std::span<const Rgb> approx) {
    if (wi.size() != reference.size() || wi.size() != approx.size())
        throw ValueError("metrics: pairs, reference values and approximate values differ in number");
    Sums total;
    for (std::size_t k = 0; k < wi.size(); ++k)
        if (finite(reference[k]) && finite(approx[k])) add_sample(total, reference[k], approx[k], wi[k].z);
    return to_metrics(total);
}

Metrics compare(const MeasurementSet& reference, const Brdf& approx, const MetricOptions& options) {
    if (options.over == Over::Directions)
        throw ValueError((reference.source.empty() ? std::string("measurements") : reference.source) +
                         ": metrics over directions need a BRDF as the reference; measurements are judged at their points");
    const double min_cos = min_cos_of(options);
    std::vector<Vec3> wi, wo;
    std::vector<Rgb> ref;
    for (const Measurement& m : reference.samples) {
        if (!(m.wi.z > min_cos && m.wo.z > min_cos)) continue;
        if (!(std::isfinite(m.f[0]) && std::isfinite(m.f[1]) && std::isfinite(m.f[2]))) continue;
        wi.push_back(m.wi);
        wo.push_back(m.wo);
        ref.push_back(m.f);
    }
    std::vector<Rgb> app(wi.size());
    approx.eval(wi, wo, app);
    Sums total;
    for (std::size_t k = 0; k < wi.size(); ++k) {
        bool finite = true;
        for (int c = 0; c < 3; ++c) finite = finite && std::isfinite(app[k][c]);
        if (finite) add_sample(total, ref[k], app[k], wi[k].z);
    }
    return to_metrics(total);
}

double eval_rate(const Brdf& brdf, std::size_t pairs, int reps) {
    if (pairs == 0 || reps < 1) throw ValueError("eval_rate: needs at least one pair and one run");
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const auto hemisphere = [&] {
        const double z = u(rng), phi = 2.0 * std::numbers::pi * u(rng);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    std::vector<Vec3> wi(pairs), wo(pairs);
    for (std::size_t k = 0; k < pairs; ++k) {
        wi[k] = hemisphere();
        wo[k] = hemisphere();
    }
    std::vector<Rgb> out(pairs);
    brdf.eval(wi, wo, out);
    std::vector<double> seconds;
    for (int r = 0; r < reps; ++r) {
        poll_stop();
        const auto start = std::chrono::steady_clock::now();
        brdf.eval(wi, wo, out);
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::nth_element(seconds.begin(), seconds.begin() + reps / 2, seconds.end());
    return static_cast<double>(pairs) / std::max(seconds[reps / 2], 1e-9);
}

}  // namespace brdfz
