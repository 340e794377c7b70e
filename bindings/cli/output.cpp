#include "output.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <mutex>

#include "brdfz/errors.h"

namespace brdfz::cli {

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

std::function<void(double)> progress_bar(const std::string& label) {
    if (!::isatty(STDERR_FILENO)) return nullptr;
    return [label, last = -1](double fraction) mutable {
        const int pct = static_cast<int>(fraction * 100.0);
        if (pct == last) return;
        last = pct;
        std::cerr << "\r" << label << " " << pct << "%" << (pct >= 100 ? "\n" : "") << std::flush;
    };
}

void add_load_options(CLI::App* cmd, LoadOptions& options) {
    cmd->add_option("--bin-position", options.position,
                    "where table samples sit in their bins: centre (default) or start")
        ->transform(CLI::CheckedTransformer(
            std::map<std::string, BinPosition>{{"start", BinPosition::Start}, {"centre", BinPosition::Centre}}));
    cmd->add_option("--lookup", options.lookup, "table lookup: nearest or linear")
        ->transform(CLI::CheckedTransformer(
            std::map<std::string, Lookup>{{"nearest", Lookup::Nearest}, {"linear", Lookup::Linear}}));
}

const char* const kOverHelp =
    "where the metrics are taken: grid (each bin of the reference's Rusinkiewicz grid once, the MERL "
    "literature's convention) or directions (--directions pairs uniform in solid angle, theta_i below "
    "--max-theta and within the reference's measured range, theta_o below --max-theta, every azimuth; "
    "each pair once: what a renderer asks for)";

void add_over_options(CLI::App* cmd, MetricOptions& options) {
    cmd->add_option("--over", options.over, kOverHelp)
        ->transform(CLI::CheckedTransformer(
            std::map<std::string, Over>{{"grid", Over::Grid}, {"directions", Over::Directions}}))
        ->default_str("grid");
    cmd->add_option("--directions", options.directions, "direction pairs drawn with --over directions")
        ->check(CLI::Range(std::size_t{1}, MetricOptions::kMaxDirections))
        ->capture_default_str();
    cmd->add_option("--seed", options.seed, "seed of those pairs")->capture_default_str();
}

bool parse_numbers(const std::string& text, double* out, int count) {
    const char* p = text.c_str();
    for (int k = 0; k < count; ++k) {
        char* end = nullptr;
        out[k] = std::strtod(p, &end);
        if (end == p) return false;
        p = end;
        while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
        if (k + 1 < count) {
            if (*p != ',') return false;
            ++p;
        }
    }
    return *p == '\0';
}

Vec3 unit_direction(const double* v, const std::string& where) {
    const Vec3 d{v[0], v[1], v[2]};
    const double n = length(d);
    if (!std::isfinite(n) || n == 0.0) throw ValueError(where + ": direction must be a finite non-zero vector");
    return (1.0 / n) * d;
}

Vec3 parse_direction(const std::string& text, const std::string& option) {
    double v[3];
    if (!parse_numbers(text, v, 3)) throw ValueError(option + ": expected x,y,z");
    return unit_direction(v, option);
}

GridSpec parse_resolution(const std::string& text) {
    GridSpec g;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%dx%dx%d%c", &g.n_theta_h, &g.n_theta_d, &g.n_phi_d, &tail) != 3)
        throw ValueError("resolution '" + text + "' is not of the form NHxNDxNP (e.g. 90x90x180)");
    g.validate();
    return g;
}

}  // namespace brdfz::cli
