#include "output.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <mutex>

#include "brdfz/control.h"
#include "brdfz/errors.h"

namespace brdfz::cli {

void append_number(std::string& out, double v) {
    // to_chars with a precision is printf's %.17g, without its locale and format parsing.
    char buf[32];
    out.append(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17).ptr);
}

std::string number(double v) {
    std::string out;
    append_number(out, v);
    return out;
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

CLI::Option* add_over_options(CLI::App* cmd, MetricOptions& options) {
    CLI::Option* over = cmd->add_option("--over", options.over, kOverHelp)
                            ->transform(CLI::CheckedTransformer(
                                std::map<std::string, Over>{{"grid", Over::Grid}, {"directions", Over::Directions}}))
                            ->default_str(over_name(options.over));
    cmd->add_option("--directions", options.directions, "direction pairs drawn with --over directions")
        ->check(CLI::Range(std::size_t{1}, MetricOptions::kMaxDirections))
        ->capture_default_str();
    cmd->add_option("--seed", options.seed, "seed of those pairs")->capture_default_str()->check(unsigned_integer());
    return over;
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

bool to_unit(const double* v, Vec3& out) {
    const Vec3 d{v[0], v[1], v[2]};
    const double n = length(d);
    if (!std::isfinite(n) || n == 0.0) return false;
    out = (1.0 / n) * d;
    return true;
}

Vec3 unit_direction(const double* v, const std::string& where) {
    Vec3 d;
    if (!to_unit(v, d)) throw ValueError(where + ": direction must be a finite non-zero vector");
    return d;
}

Vec3 parse_direction(const std::string& text, const std::string& option) {
    double v[3];
    if (!parse_numbers(text, v, 3)) throw ValueError(option + ": expected x,y,z");
    return unit_direction(v, option);
}

CLI::Validator unsigned_integer() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            std::uint64_t v = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (!text.empty() && ec == std::errc() && end == text.data() + text.size()) return {};
            const std::string range = "[0, " + std::to_string(UINT64_MAX) + "]";
            // Digits, with a minus sign or too many of them, are a whole number outside the range.
            const std::size_t digits = text.starts_with('-') ? 1 : 0;
            if (text.size() > digits && text.find_first_not_of("0123456789", digits) == std::string::npos)
                return "'" + text + "' is outside " + range;
            return "'" + text + "' is not an integer in " + range;
        },
        "UINT");
}

void add_threads_option(CLI::App* cmd, int& threads) {
    cmd->add_option("--threads", threads, "0: one per hardware thread; at most " + std::to_string(kMaxThreads))
        ->capture_default_str()
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
                long long n = 0;
                const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
                if (ec == std::errc::result_out_of_range || (ec == std::errc() && n > kMaxThreads))
                    return text + " is above the limit of " + std::to_string(kMaxThreads) + " threads";
                return {};
            },
            ""));
}

GridSpec parse_resolution(const std::string& text) {
    const auto malformed = [&] {
        return ValueError("resolution '" + text + "' is not of the form NHxNDxNP (e.g. 90x90x180)");
    };
    GridSpec g;
    int* const axes[3] = {&g.n_theta_h, &g.n_theta_d, &g.n_phi_d};
    const char* p = text.data();
    const char* const last = p + text.size();
    for (int k = 0; k < 3; ++k) {
        if (k > 0 && (p == last || *p++ != 'x')) throw malformed();
        // Digits only: sscanf's %d took signs and spaces, and wrapped values beyond int's range round.
        if (p == last || *p < '0' || *p > '9') throw malformed();
        const auto [end, ec] = std::from_chars(p, last, *axes[k]);
        if (ec == std::errc::result_out_of_range)
            throw ValueError("resolution '" + text + "': every axis must be in [1, " + std::to_string(GridSpec::kMaxAxis) + "]");
        p = end;
    }
    if (p != last) throw malformed();
    g.validate();
    return g;
}

}  // namespace brdfz::cli
