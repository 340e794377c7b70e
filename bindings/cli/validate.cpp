// brdfz validate FILE: the library's plausibility checks (brdfz/validate.h), each reporting the
// offending directions. A report goes to stdout; when a check fails the command ends with one error
// line and status 1.
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/validate.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

std::string rgb(const Rgb& v) {
    char buf[80];
    std::snprintf(buf, sizeof buf, "%.4g,%.4g,%.4g", v[0], v[1], v[2]);
    return buf;
}

void print_text(const std::string& file, const ValidationReport& report, std::ostream& os) {
    os << file << "\n";
    for (const ValidationCheck& c : report.checks) {
        char line[160];
        std::snprintf(line, sizeof line, "  %-15s %-5s %zu of %zu %s fail\n", c.name.c_str(), c.failed ? "FAIL" : "ok",
                      c.failed, c.tested, c.unit.c_str());
        os << line;
        if (c.error) os << "      error " << *c.error << " (cos_rmse_rel of f(wo, wi) against f(wi, wo), over directions)\n";
        for (const ValidationOffence& o : c.worst) {
            if (c.name == "energy") {
                std::snprintf(line, sizeof line, "      theta %5.1f deg: ", o.theta_i_deg);
                os << line << "albedo viewed " << rgb(o.f) << "; reflectance lit " << rgb(o.g) << "\n";
                continue;
            }
            std::snprintf(line, sizeof line, "      theta_i %5.1f  theta_o %5.1f  dphi %5.1f deg: ", o.theta_i_deg,
                          o.theta_o_deg, o.dphi_deg);
            os << line << "f = " << rgb(o.f);
            if (c.name == "reciprocity") os << "  swapped " << rgb(o.g);
            os << "\n";
        }
    }
}

void print_json(const std::string& file, const ValidationReport& report, std::ostream& os) {
    JsonWriter j(os);
    j.begin_object();
    j.key("file").value(file);
    j.key("ok").value(report.ok());
    for (const ValidationCheck& c : report.checks) {
        j.key(c.name).begin_object();
        j.key("ok").value(c.ok());
        j.key("tested").value(c.tested);
        j.key("failed").value(c.failed);
        if (c.error) j.key("error").value(*c.error);
        j.key("worst").begin_array();
        for (const ValidationOffence& o : c.worst) {
            j.begin_object();
            j.key("theta_i_deg").value(o.theta_i_deg).key("theta_o_deg").value(o.theta_o_deg).key("dphi_deg").value(o.dphi_deg);
            j.key(c.f_name).begin_array();
            for (double v : o.f) j.value(v);
            j.end_array();
            if (!c.g_name.empty()) {
                j.key(c.g_name).begin_array();
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
        ValidateOptions options;
        options.grid = parse_resolution(args->res);
        options.theta_deg = parse_angles(args->thetas);
        options.rtol = args->rtol;
        options.atol = args->atol;
        options.albedo_tol = args->albedo_tol;
        const Loaded loaded = load(args->file, args->load);
        const ValidationReport report = validate(*loaded.brdf, options);
        if (args->json)
            print_json(args->file, report, std::cout);
        else
            print_text(args->file, report, std::cout);
        if (!report.ok()) throw Error(args->file + ": validation failed: " + report.failed_names());
    });
}

}  // namespace brdfz::cli
