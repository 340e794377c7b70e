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

}  // namespace

Metrics compare(const Brdf& reference, const Brdf& approx, const MetricOptions& options) {
    // Extrapolated reference values (beyond its measured range) are no measure of error.
    const double theta_max = reference.measured_theta_max();
    const double min_cos = theta_max < std::numbers::pi / 2 ? std::max(min_cos_of(options), std::cos(theta_max))
                                                            : min_cos_of(options);
    const Table* ref_table = reference.stored_table();
    const GridSpec g = ref_table ? ref_table->grid() : options.grid;
    g.validate();

    const int workers = detail::resolve_threads(options.threads);
    std::vector<Sums> sums(workers);
    std::vector<std::vector<Rgb>> ref_f(workers), app_f(workers);
    detail::sweep_slices(g, workers, [&](int w, int ih, std::span<const Vec3> wi, std::span<const Vec3> wo) {
        ref_f[w].resize(wi.size());
        app_f[w].resize(wi.size());
        if (!ref_table) reference.eval(wi, wo, ref_f[w]);
        approx.eval(wi, wo, app_f[w]);
        Sums& s = sums[w];
        const std::size_t base = g.index(ih, 0, 0);
        for (std::size_t k = 0; k < wi.size(); ++k) {
            if (!(wi[k].z > min_cos && wo[k].z > min_cos)) continue;
            Rgb ref = ref_f[w][k];
            if (ref_table) {
                if (!ref_table->valid(base + k)) continue;
                for (int c = 0; c < 3; ++c) ref[c] = ref_table->at(base + k, c);
            }
            bool finite = true;
            for (int c = 0; c < 3; ++c) finite = finite && std::isfinite(ref[c]) && std::isfinite(app_f[w][k][c]);
            if (!finite) continue;  // a reference without a value at this bin is not a sample
            add_sample(s, ref, app_f[w][k], wi[k].z);
        }
    });

    Sums total;
    for (const Sums& s : sums) {
        total.n += s.n;
        total.negatives += s.negatives;
        for (int c = 0; c < 3; ++c) {
            total.sq[c] += s.sq[c];
            total.ref_sq[c] += s.ref_sq[c];
            total.log_sq[c] += s.log_sq[c];
            total.cbrt_sq[c] += s.cbrt_sq[c];
        }
    }
    return to_metrics(total);
}

Metrics compare(const MeasurementSet& reference, const Brdf& approx, const MetricOptions& options) {
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
        const auto start = std::chrono::steady_clock::now();
        brdf.eval(wi, wo, out);
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::nth_element(seconds.begin(), seconds.begin() + reps / 2, seconds.end());
    return static_cast<double>(pairs) / std::max(seconds[reps / 2], 1e-9);
}

}  // namespace brdfz
