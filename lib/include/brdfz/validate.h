// Physical plausibility checks of a BRDF (`brdfz validate`, Python brdfz.validate), each counting what
// it tested and what failed and keeping the worst offending direction pairs:
//   non-negativity  a table's stored values, or f at every bin of a grid for other representations;
//   reciprocity     f(wi, wo) against f(wo, wi) on a fixed set of direction pairs, and the
//                   reciprocity error over direction pairs (metrics.h) as a number;
//   energy          hemispherical reflectance ≤ 1 + tolerance at a set of elevations, both as the
//                   directional albedo ∫ f(wi, wo) cosθi dωi at θo and, for light arriving at θi,
//                   ∫ f(wi, wo) cosθo dωo (they differ only for non-reciprocal data).
// The report is data: the CLI prints it as text or JSON, Python returns it; a check that measures a
// further figure carries it as a member of its ValidationCheck.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/table.h"

namespace brdfz {

struct ValidateOptions {
    GridSpec grid{90, 90, 180};  // non-negativity: bins evaluated when the BRDF is not a table
    double rtol = 0.05;          // reciprocity: a pair fails where, in any channel,
    double atol = 1e-3;          //   |f − f_swapped| > rtol·max(|f|, |f_swapped|) + atol (1/sr)
    std::vector<double> theta_deg{0, 10, 20, 30, 40, 50, 60, 70, 80, 85};  // energy: elevations, [0, 90)
    double albedo_tol = 0.01;    // energy: allowed excess over 1 (the quadrature's error)
    std::size_t worst = 5;       // offending pairs kept per check
};

// An offending direction pair and the value(s) involved; larger badness is worse.
struct ValidationOffence {
    double theta_i_deg = 0, theta_o_deg = 0, dphi_deg = 0;  // dphi = φo − φi in [0, 360)
    Rgb f{}, g{};
    double badness = 0;
};

struct ValidationCheck {
    std::string name;            // "non-negativity", "reciprocity" or "energy"
    std::string unit;            // what was tested: "bins", "pairs", "elevations"
    std::string f_name, g_name;  // what an offence's f and g hold (g_name empty: g is not used)
    std::size_t tested = 0, failed = 0;
    std::vector<ValidationOffence> worst;  // the worst first, at most ValidateOptions::worst
    // reciprocity: the source's reciprocity error, reciprocity_error()'s cos_rmse_rel (metrics.h);
    // none for the other checks.
    std::optional<double> error;
    bool ok() const { return failed == 0; }
};

struct ValidationReport {
    std::vector<ValidationCheck> checks;  // non-negativity, reciprocity, energy
    bool ok() const;
    std::string failed_names() const;  // the failed checks' names, ", "-separated; empty when ok
};

// ValueError for an invalid grid, a tolerance that is negative or NaN, or no or out-of-range elevations.
ValidationReport validate(const Brdf& brdf, const ValidateOptions& options = {});

}  // namespace brdfz
