// brdfz validate FILE: physical plausibility checks, each reporting the offending directions.
//   non-negativity  a table's stored values, or f at every bin of a grid for other representations;
//   reciprocity     f(wi, wo) against f(wo, wi) on a fixed set of direction pairs;
//   energy          hemispherical reflectance ≤ 1 + tolerance at a set of elevations, both as the
//                   directional albedo ∫ f(wi, wo) cosθi dωi at θo and, for light arriving at θi,
//                   ∫ f(wi, wo) cosθo dωo (they differ only for non-reciprocal data).
// A report goes to stdout; when a check fails the command ends with one error line and status 1.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/metrics.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::size_t kWorst = 5;  // offending directions listed per check

// An offending direction pair, its values, and how bad it is (larger is worse).
struct Offence {
    double theta_i, theta_o, dphi;  // degrees; dphi = φo − φi
    Rgb f, g;                       // the value(s) involved: f, and for reciprocity f with wi, wo swapped
    double badness;
};

struct Check {
    std::string name;
    std::size_t tested = 0, failed = 0;
    std::string unit;  // what was tested ("bins", "pairs", "elevations")
    std::vector<Offence> worst;
    double error = -1;  // reciprocity: reciprocity_error()'s cos_rmse_rel (metrics.h); -1: not a number this check gives

    void offend(const Offence& o) {
        ++failed;
        worst.push_back(o);
        std::sort(worst.begin(), worst.end(), [](const Offence& a, const Offence& b) { return a.badness > b.badness; });
        if (worst.size() > kWorst) worst.pop_back();
    }
};

Offence at(const Vec3& wi, const Vec3& wo, const Rgb& f, const Rgb& g, double badness) {
    double dphi = (std::atan2(wo.y, wo.x) - std::atan2(wi.y, wi.x)) / kDeg;
    if (dphi < 0.0) dphi += 360.0;
    return {elevation(wi) / kDeg, elevation(wo) / kDeg, dphi, f, g, badness};
}

Check non_negativity(const Brdf& brdf, const GridSpec& grid) {
    Check c{"non-negativity", 0, 0, "bins", {}};
    const auto* tab = dynamic_cast<const TabularBrdf*>(&brdf);
    const GridSpec& g = tab ? tab->table().grid() : grid;
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
        if (tab) {
            for (std::size_t k = 0; k < f.size(); ++k) {
                const std::size_t bin = g.index(ih, 0, 0) + k;
                f[k] = {tab->table().at(bin, 0), tab->table().at(bin, 1), tab->table().at(bin, 2)};
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
            ++c.tested;
            if (lowest < 0.0) c.offend(at(wi[k], wo[k], f[k], f[k], -lowest));
        }
    }
    return c;
}

Check reciprocity(const Brdf& brdf, double rtol, double atol) {
    Check c{"reciprocity", 0, 0, "pairs", {}};
    for (double ti = 2.5; ti < 85.0; ti += 5.0)
        for (double to = 2.5; to < 85.0; to += 5.0)
            for (double dphi = 0.0; dphi < 360.0; dphi += 22.5) {
                const Vec3 wi = spherical_direction(ti * kDeg, 0.0), wo = spherical_direction(to * kDeg, dphi * kDeg);
                const Rgb f = brdf.eval(wi, wo), g = brdf.eval(wo, wi);
                ++c.tested;
                double worst = 0.0;
                bool bad = false;
                for (int ch = 0; ch < 3; ++ch) {
                    const double diff = std::abs(f[ch] - g[ch]), scale = std::max(std::abs(f[ch]), std::abs(g[ch]));
                    bad |= diff > rtol * scale + atol;
                    worst = std::max(worst, diff / (scale + atol));
                }
                if (bad) c.offend(at(wi, wo, f, g, worst));
            }
    c.error = reciprocity_error(brdf).cos_rmse_rel.mean;
    return c;
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

Check energy(const Brdf& brdf, const std::vector<double>& thetas, double tol) {
    Check c{"energy", 0, 0, "elevations", {}};
    const Transposed incident(brdf);
    for (double t : thetas) {
        ++c.tested;
        const Rgb viewed = directional_albedo(brdf, t * kDeg), lit = directional_albedo(incident, t * kDeg);
        const double worst = std::max({viewed[0], viewed[1], viewed[2], lit[0], lit[1], lit[2]});
        // Reported as θi = θo = t: the albedo viewed at t (f) and the reflectance lit from t (g).
        if (worst > 1.0 + tol) c.offend({t, t, 0.0, viewed, lit, worst});
    }
    return c;
}

std::string rgb(const Rgb& v) {
    char buf[80];
    std::snprintf(buf, sizeof buf, "%.4g,%.4g,%.4g", v[0], v[1], v[2]);
    return buf;
}

void print_text(const std::string& file, const std::vector<Check>& checks, std::ostream& os) {
    os << file << "\n";
    for (const Check& c : checks) {
        char line[160];
        std::snprintf(line, sizeof line, "  %-15s %-5s %zu of %zu %s fail\n", c.name.c_str(), c.failed ? "FAIL" : "ok",
                      c.failed, c.tested, c.unit.c_str());
        os << line;
        if (c.error >= 0) os << "      error " << c.error << " (cos_rmse_rel of f(wo, wi) against f(wi, wo), over directions)\n";
        for (const Offence& o : c.worst) {
            if (c.name == "energy") {
                std::snprintf(line, sizeof line, "      theta %5.1f deg: ", o.theta_i);
                os << line << "albedo viewed " << rgb(o.f) << "; reflectance lit " << rgb(o.g) << "\n";
                continue;
            }
            std::snprintf(line, sizeof line, "      theta_i %5.1f  theta_o %5.1f  dphi %5.1f deg: ", o.theta_i,
                          o.theta_o, o.dphi);
            os << line << "f = " << rgb(o.f);
            if (c.name == "reciprocity") os << "  swapped " << rgb(o.g);
            os << "\n";
        }
    }
}

void print_json(const std::string& file, const std::vector<Check>& checks, std::ostream& os) {
    JsonWriter j(os);
    j.begin_object();
    j.key("file").value(file);
    bool ok = true;
    for (const Check& c : checks) ok &= c.failed == 0;
    j.key("ok").value(ok);
    for (const Check& c : checks) {
        j.key(c.name).begin_object();
        j.key("ok").value(c.failed == 0);
        j.key("tested").value(c.tested);
        j.key("failed").value(c.failed);
        if (c.error >= 0) j.key("error").value(c.error);
        j.key("worst").begin_array();
        for (const Offence& o : c.worst) {
            j.begin_object();
            j.key("theta_i_deg").value(o.theta_i).key("theta_o_deg").value(o.theta_o).key("dphi_deg").value(o.dphi);
            j.key(c.name == "energy" ? "albedo_viewed" : "f").begin_array();
            for (double v : o.f) j.value(v);
            j.end_array();
            if (c.name != "non-negativity") {
                j.key(c.name == "energy" ? "reflectance_lit" : "f_swapped").begin_array();
                for (double v : o.g) j.value(v);
                j.end_array();
            }
            j.end_object();
        }
        j.end_array();
        j.end_object();
    }
    j.end_object();
    os << "\n";
}

std::vector<double> parse_angles(const std::string& text) {
    std::vector<double> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (end == item.c_str() || *end != '\0' || !(v >= 0.0 && v < 90.0))
            throw ValueError("--theta: '" + item + "' is not an elevation in [0, 90) degrees");
        out.push_back(v);
    }
    if (out.empty()) throw ValueError("--theta: no elevations given");
    return out;
}

}  // namespace

void add_validate(CLI::App& app) {
    struct Args {
        std::string file, res = "90x90x180", thetas = "0,10,20,30,40,50,60,70,80,85";
        double rtol = 0.05, atol = 1e-3, albedo_tol = 0.01;
        bool json = false;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("validate", "check non-negativity, reciprocity and energy conservation "
                                                   "(exit status 1 on violations)");
    cmd->add_option("FILE", args->file, "input file")->required();
    cmd->add_option("--res", args->res, "grid for the non-negativity check of non-tabular data")->capture_default_str();
    cmd->add_option("--theta", args->thetas, "elevations (degrees) for the energy check")->capture_default_str();
    cmd->add_option("--rtol", args->rtol, "reciprocity: relative tolerance")->capture_default_str();
    cmd->add_option("--atol", args->atol, "reciprocity: absolute tolerance (1/sr)")->capture_default_str();
    cmd->add_option("--albedo-tol", args->albedo_tol, "energy: allowed excess over 1 (quadrature error)")
        ->capture_default_str();
    cmd->add_flag("--json", args->json, "print JSON");
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        const GridSpec grid = parse_resolution(args->res);
        const std::vector<double> thetas = parse_angles(args->thetas);
        const Loaded loaded = load(args->file, args->load);
        const std::vector<Check> checks{non_negativity(*loaded.brdf, grid),
                                        reciprocity(*loaded.brdf, args->rtol, args->atol),
                                        energy(*loaded.brdf, thetas, args->albedo_tol)};
        if (args->json)
            print_json(args->file, checks, std::cout);
        else
            print_text(args->file, checks, std::cout);
        std::string failed;
        for (const Check& c : checks)
            if (c.failed) failed += (failed.empty() ? "" : ", ") + c.name;
        if (!failed.empty()) throw Error(args->file + ": validation failed: " + failed);
    });
}

}  // namespace brdfz::cli
