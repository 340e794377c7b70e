// Helpers shared by the benchmark programs: timing, medians, arguments, a synthetic table, a temporary
// directory, the eval benchmarks' direction pairs.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/frame.h"
#include "brdfz/table.h"

namespace bench {

using Clock = std::chrono::steady_clock;

inline double ms_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
}

// Median rather than mean: on a shared machine the outliers are other processes, not our code.
inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

struct Args {
    std::string path;  // empty: use synthetic data
    int reps;
};

// "[FILE.binary] [--reps N]". A bad command line prints the usage and exits: this is a program.
inline Args parse_args(int argc, char** argv, int default_reps) {
    Args args{"", default_reps};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--reps" && i + 1 < argc) {
            args.reps = std::atoi(argv[++i]);
        } else if (!a.empty() && a[0] != '-' && args.path.empty()) {
            args.path = a;
        } else {
            args.reps = 0;
            break;
        }
    }
    if (args.reps < 1) {
        std::fprintf(stderr, "usage: %s [FILE.binary] [--reps N]   (N >= 1, default %d)\n", argv[0], default_reps);
        std::exit(2);
    }
    return args;
}

// Uniform in solid angle on the upper hemisphere: cosθ is uniform on [0, 1).
inline brdfz::Vec3 uniform_hemisphere(double u1, double u2) {
    const double z = u1;
    const double r = std::sqrt(std::fmax(0.0, 1.0 - z * z));
    const double phi = 2.0 * std::numbers::pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// A fresh directory under the system temp dir, removed with everything in it on scope exit.
class TempDir {
public:
    TempDir() {
        std::string name = (std::filesystem::temp_directory_path() / "brdfz-bench-XXXXXX").string();
        if (!mkdtemp(name.data())) throw brdfz::IoError(name, "cannot create a temporary directory");
        path_ = name;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// The eval benchmarks' direction pairs: wi and wo both uniform on the upper hemisphere, the same
// pairs (one seed) in every program, so that their figures compare.
constexpr std::size_t kPairs = std::size_t{1} << 20;
struct Pairs {
    std::vector<brdfz::Vec3> wi, wo;
};
inline Pairs uniform_pairs(std::size_t n = kPairs) {
    Pairs p{std::vector<brdfz::Vec3>(n), std::vector<brdfz::Vec3>(n)};
    std::mt19937_64 rng(20261122);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (std::size_t k = 0; k < n; ++k) {
        p.wi[k] = uniform_hemisphere(u01(rng), u01(rng));
        p.wo[k] = uniform_hemisphere(u01(rng), u01(rng));
    }
    return p;
}

// Every channel summed: printed as a checksum, so that no evaluation can be dropped as unused.
inline double sum_of(std::span<const brdfz::Rgb> out) {
    double s = 0.0;
    for (const brdfz::Rgb& f : out) s += f[0] + f[1] + f[2];
    return s;
}

// "[--out FILE.csv] [--spec SPEC]... [FILE...]", the command line of the sweeps over representations
// (compress_sweep, stability). No --spec: the program's defaults. A bad command line prints the usage
// and exits.
struct SweepArgs {
    std::string out;
    std::vector<std::string> specs;
    std::vector<std::filesystem::path> files;
};

inline SweepArgs parse_sweep_args(int argc, char** argv, const char* default_out, const std::vector<std::string>& default_specs) {
    SweepArgs args{default_out, {}, {}};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--out" && i + 1 < argc) {
            args.out = argv[++i];
        } else if (a == "--spec" && i + 1 < argc) {
            args.specs.emplace_back(argv[++i]);
        } else if (!a.empty() && a[0] != '-') {
            args.files.emplace_back(a);
        } else {
            std::fprintf(stderr, "usage: %s [--out FILE.csv] [--spec SPEC]... [FILE...]\n", argv[0]);
            std::exit(2);
        }
    }
    if (args.specs.empty()) args.specs = default_specs;
    return args;
}

// A smooth positive RGB function of the bin angles: a specular peak in θh over a diffuse floor, with
// θd (Fresnel-like) and φd terms so every axis of a linear lookup does real work.
inline brdfz::Table synthetic_table(const brdfz::GridSpec& g) {
    brdfz::Table t(g);
    for (int ih = 0; ih < g.n_theta_h; ++ih) {
        const double th = g.theta_h_at(ih);
        const double spec = std::exp(-th * th / 0.02);
        for (int id = 0; id < g.n_theta_d; ++id) {
            const double fres = 1.0 + std::pow(std::sin(g.theta_d_at(id)), 5.0);
            for (int ip = 0; ip < g.n_phi_d; ++ip) {
                const double aniso = 1.0 + 0.1 * std::cos(2.0 * g.phi_d_at(ip));
                const double s = spec * fres * aniso;
                t.set(g.index(ih, id, ip), {0.05 + 2.0 * s, 0.04 + 1.5 * s, 0.02 + 1.0 * s});
            }
        }
    }
    return t;
}

}  // namespace bench
