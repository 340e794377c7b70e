#include "brdfz/validate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "brdfz/albedo.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/metrics.h"
#include "brdfz/table.h"

namespace brdfz {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

class Tally {
public:
    Tally(ValidationCheck check, std::size_t keep) : c_(std::move(check)), keep_(keep) {}
    void test() { ++c_.tested; }
    void offend(const ValidationOffence& o) {
        ++c_.failed;
        c_.worst.push_back(o);
        std::sort(c_.worst.begin(), c_.worst.end(),
                  [](const ValidationOffence& a, const ValidationOffence& b) { return a.badness > b.badness; });
        if (c_.worst.size() > keep_) c_.worst.pop_back();
    }
    ValidationCheck done() && { return std::move(c_); }

private:
    ValidationCheck c_;
    std::size_t keep_;
};

ValidationOffence at(const Vec3& wi, const Vec3& wo, const Rgb& f, const Rgb& g, double badness) {
    double dphi = (std::atan2(wo.y, wo.x) - std::atan2(wi.y, wi.x)) / kDeg;
    if (dphi < 0.0) dphi += 360.0;
    return {elevation(wi) / kDeg, elevation(wo) / kDeg, dphi, f, g, badness};
}

ValidationCheck non_negativity(const Brdf& brdf, const ValidateOptions& options) {
    Tally c({"non-negativity", "bins", "f", "", 0, 0, {}, {}}, options.worst);
    const Table* table = brdf.stored_table();
    const GridSpec& g = table ? table->grid() : options.grid;
    std::vector<Vec3> wi, wo;
    std::vector<Rgb> f;
    for (int ih = 0; ih < g.n_theta_h; ++ih) {
        // One θh slice at a time: bounded memory, and evaluation in batches.
        wi.clear();
        wo.clear();
        for (int id = 0; id < g.n_theta_d; ++id)
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const auto [a, b] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                wi.push_back(a);
                wo.push_back(b);
            }
        f.resize(wi.size());
        if (table) {
            for (std::size_t k = 0; k < f.size(); ++k) {
                const std::size_t bin = g.index(ih, 0, 0) + k;
                f[k] = {table->at(bin, 0), table->at(bin, 1), table->at(bin, 2)};
            }
        } else {
            brdf.eval(wi, wo, f);
        }
        for (std::size_t k = 0; k < f.size(); ++k) {
            // Bins below the horizon are never evaluated, and a table's unmeasured entries (NaN) are
            // not values.
            if (!(wi[k].z > 0.0 && wo[k].z > 0.0)) continue;
            double lowest = std::numeric_limits<double>::infinity();
            for (double v : f[k])
                if (!std::isnan(v)) lowest = std::min(lowest, v);
            if (lowest == std::numeric_limits<double>::infinity()) continue;
            c.test();
            if (lowest < 0.0) c.offend(at(wi[k], wo[k], f[k], f[k], -lowest));
        }
    }
    return std::move(c).done();
}

ValidationCheck reciprocity(const Brdf& brdf, const ValidateOptions& options) {
    Tally c({"reciprocity", "pairs", "f", "f_swapped", 0, 0, {}, {}}, options.worst);
    for (double ti = 2.5; ti < 85.0; ti += 5.0)
        for (double to = 2.5; to < 85.0; to += 5.0)
            for (double dphi = 0.0; dphi < 360.0; dphi += 22.5) {
                const Vec3 wi = spherical_direction(ti * kDeg, 0.0), wo = spherical_direction(to * kDeg, dphi * kDeg);
                const Rgb f = brdf.eval(wi, wo), g = brdf.eval(wo, wi);
                c.test();
                double worst = 0.0;
                bool bad = false;
                for (int ch = 0; ch < 3; ++ch) {
                    const double diff = std::abs(f[ch] - g[ch]), scale = std::max(std::abs(f[ch]), std::abs(g[ch]));
                    bad |= diff > options.rtol * scale + options.atol;
                    worst = std::max(worst, diff / (scale + options.atol));
                }
                if (bad) c.offend(at(wi, wo, f, g, worst));
            }
    ValidationCheck out = std::move(c).done();
    out.error = reciprocity_error(brdf).cos_rmse_rel.mean;
    return out;
}

// f with the roles of the two directions exchanged: its directional albedo at θ is the reflectance
// for light arriving from θ.
class Transposed final : public Brdf {
public:
    explicit Transposed(const Brdf& b) : b_(b) {}
    int channels() const override { return b_.channels(); }
    std::size_t nbytes() const override { return b_.nbytes(); }
    std::string describe() const override { return b_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return b_.eval(wo, wi); }

private:
    const Brdf& b_;
};

ValidationCheck energy(const Brdf& brdf, const ValidateOptions& options) {
    Tally c({"energy", "elevations", "albedo_viewed", "reflectance_lit", 0, 0, {}, {}}, options.worst);
    const Transposed incident(brdf);
    for (double t : options.theta_deg) {
        c.test();
        const Rgb viewed = directional_albedo(brdf, t * kDeg), lit = directional_albedo(incident, t * kDeg);
        const double worst = std::max({viewed[0], viewed[1], viewed[2], lit[0], lit[1], lit[2]});
        // Reported as θi = θo = t: the albedo viewed at t (f) and the reflectance lit from t (g).
        if (worst > 1.0 + options.albedo_tol) c.offend({t, t, 0.0, viewed, lit, worst});
    }
    return std::move(c).done();
}

}  // namespace

bool ValidationReport::ok() const {
    return std::all_of(checks.begin(), checks.end(), [](const ValidationCheck& c) { return c.ok(); });
}

std::string ValidationReport::failed_names() const {
    std::string out;
    for (const ValidationCheck& c : checks)
        if (!c.ok()) out += (out.empty() ? "" : ", ") + c.name;
    return out;
}

ValidationReport validate(const Brdf& brdf, const ValidateOptions& options) {
    options.grid.validate();
    if (!(options.rtol >= 0.0 && options.atol >= 0.0 && options.albedo_tol >= 0.0))
        throw ValueError("validate: rtol, atol and albedo_tol must be >= 0");
    if (options.theta_deg.empty()) throw ValueError("validate: no elevations for the energy check");
    for (double t : options.theta_deg)
        if (!(t >= 0.0 && t < 90.0))
            throw ValueError("validate: elevation " + std::to_string(t) + " is not in [0, 90) degrees");
    return {{non_negativity(brdf, options), reciprocity(brdf, options), energy(brdf, options)}};
}

}  // namespace brdfz
