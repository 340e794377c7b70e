// The stability study: where does each method break? Every representation setting (and each fitted
// model and loss) on every material class — diffuse, glossy plastic, metal, near-mirror,
// retro-reflective, fabric-like sheen, data with missing bins, noisy data (synthetic, so the truth is
// known) plus the shared real data — with the failure signs the study looks for:
//   build     an error (message kept), or the fit's status (no_convergence, hit_bounds) and its
//             poor-fit warning (fit.h: converged, but the model misses the data)
//   error     cos_rmse_rel and log_rmse against the source (blow-up: cos_rmse_rel > 0.5)
//   bad       NaN, Inf or negative values over 10^5 random direction pairs
//   grazing   image error under grazing views (75–88°) divided by that under near-normal views
//   sampler   sampler_variance_ratio (albedo.h) at θo = 60°: the samples the representation's sampler
//             needs, against cosine sampling, for the same noise in the albedo estimate, with a
//             relative spread of 0.1 counting as ideal. Variance blow-up: > 1.5
// Writes a CSV (one row per method and material) and a line per row on stderr. scripts/stability runs
// it once per (material, spec) as brdfz.batch tasks and draws the Markdown table and heat map from
// the rows (brdfz.stability); docs/stability.md holds the study's tables and what was fixed.
//   stability [--out stability.csv] [--spec SPEC]... [--synthetic NAME|none]... [--list] [FILE...]
// --synthetic: only these synthetic classes (default: all; none: only the files). --list: the
// synthetic classes and the default specs, one per line ("synthetic NAME", "spec SPEC").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "brdfz/albedo.h"
#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/tabular.h"
#include "brdfz/select.h"
#include "common.h"
#include "brdfz/tabulate.h"

namespace fs = std::filesystem;
using namespace brdfz;

namespace {

const std::vector<std::string> kDefaultSpecs = {
    "analytic:lambert+ggx,loss=log",  "analytic:lambert+ggx,loss=cos", "analytic:lambert+ggx,loss=cbrt",
    "analytic:lambert+beckmann",      "analytic:lambert+ggx+ggx",      "analytic:lambert+blinn_phong",
    "analytic:lambert+ward",          "analytic:lambert+lafortune",    "analytic:lambert+ashikhmin_shirley",
    "tabular:res=16x16x32",           "tabular:res=16x16x32,dtype=u8log", "tabular:res=45x45x90,dtype=f16",
    "bivariate:res=90x90",            "svd:rank=2,space=log",          "svd:rank=4,space=linear",
    "nmf:rank=2",
};

struct Material {
    std::string name, cls;
    std::unique_ptr<Brdf> brdf;
};

std::unique_ptr<Brdf> table_of(const Brdf& b) {
    return std::make_unique<TabularBrdf>(tabulate(b).table);
}

const std::vector<std::string> kSynthetic = {"diffuse", "plastic", "metal", "mirror", "retro", "sheen", "holes", "noisy"};

// Synthetic classes: analytic truths tabulated at MERL resolution (what a measurement would give);
// the `wanted` ones of kSynthetic, in its order.
std::vector<Material> synthetic(const std::vector<std::string>& wanted) {
    std::vector<Material> out;
    const auto want = [&](const char* name) { return std::find(wanted.begin(), wanted.end(), name) != wanted.end(); };
    const auto add = [&](std::string name, std::string cls, const char* model, std::vector<double> p) {
        if (want(name.c_str())) out.push_back({std::move(name), std::move(cls), table_of(AnalyticBrdf(model, std::move(p)))});
    };
    add("diffuse", "diffuse", "lambert", {0.6, 0.5, 0.4});
    add("plastic", "glossy plastic", "lambert+ggx_dielectric", {0.3, 0.05, 0.05, 1, 1, 1, 0.12, 1.5});
    add("metal", "metal", "ggx_conductor", {1, 1, 1, 0.15, 0.18, 0.42, 1.37, 3.42, 2.35, 1.77});
    add("mirror", "near-mirror", "ggx", {1, 1, 1, 0.004, 0.9});
    add("retro", "retro-reflective", "lambert+lafortune", {0.1, 0.1, 0.1, 0.8, 0.8, 0.8, 1.0, 1.0, 30});
    add("sheen", "fabric-like sheen", "lambert+lafortune", {0.3, 0.1, 0.1, 0.6, 0.3, 0.3, -1.0, 0.2, 6});
    // Missing bins: the plastic with every bin of 30% of the (θh, θd) cells unmeasured.
    if (want("holes")) {
        Table t = tabulate(AnalyticBrdf("lambert+ggx_dielectric", {0.3, 0.05, 0.05, 1, 1, 1, 0.12, 1.5})).table;
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        const GridSpec& g = t.grid();
        for (int ih = 0; ih < g.n_theta_h; ++ih)
            for (int id = 0; id < g.n_theta_d; ++id)
                if (u(rng) < 0.3)
                    for (int ip = 0; ip < g.n_phi_d; ++ip) t.invalidate(g.index(ih, id, ip));
        out.push_back({"holes", "missing bins", std::make_unique<TabularBrdf>(std::move(t))});
    }
    // Noisy: the metal with 20% multiplicative noise and an additive floor that dips below zero.
    if (want("noisy")) {
        Table t = tabulate(AnalyticBrdf("ggx_conductor", {1, 1, 1, 0.15, 0.18, 0.42, 1.37, 3.42, 2.35, 1.77})).table;
        std::mt19937_64 rng(6);
        std::normal_distribution<double> n(0.0, 1.0);
        for (std::size_t b = 0; b < t.bins(); ++b) {
            if (!t.valid(b)) continue;
            Rgb f;
            for (int c = 0; c < 3; ++c) f[c] = t.at(b, c) * (1.0 + 0.2 * n(rng)) + 0.002 * n(rng);
            t.set(b, f);
        }
        out.push_back({"noisy", "noisy data", std::make_unique<TabularBrdf>(std::move(t))});
    }
    return out;
}

struct Row {
    std::string material, cls, spec, status = "ok";
    std::size_t bytes = 0;
    double cos_rel = NAN, log_rmse = NAN, grazing = NAN, sampler = NAN, rate = 0, seconds = 0;
    std::size_t bad = 0;
    std::vector<std::string> flags;
};

std::size_t bad_values(const Brdf& b) {
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const std::size_t n = 100000;
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 1e-9});
        wo[k] = normalize(Vec3{u(rng), u(rng), std::abs(u(rng)) + 1e-9});
    }
    std::vector<Rgb> f(n);
    b.eval(wi, wo, f);
    std::size_t bad = 0;
    for (const Rgb& v : f) bad += !(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) && v[0] >= 0 && v[1] >= 0 && v[2] >= 0);
    return bad;
}

Scene view_scene(double from_deg, double to_deg) {
    SceneDescription d;
    // Views in a ring of elevations: a cone around the normal minus the inner part is not expressible,
    // so use a cone around a tilted axis spanning [from, to].
    const double mid = 0.5 * (from_deg + to_deg) * std::numbers::pi / 180.0;
    d.views.push_back(ViewCone{spherical_direction(mid, 0.0), 0.5 * (to_deg - from_deg), 256});
    d.environment = Environment{1.0, 64};
    return build_scene(d);
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

}  // namespace

int main(int argc, char** argv) {
    // --synthetic and --list here, the sweep's own arguments in parse_sweep_args.
    std::vector<char*> rest = {argv[0]};
    std::vector<std::string> wanted;
    bool none = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--list") {
            for (const std::string& n : kSynthetic) std::printf("synthetic %s\n", n.c_str());
            for (const std::string& spec : kDefaultSpecs) std::printf("spec %s\n", spec.c_str());
            return 0;
        }
        if (a == "--synthetic" && i + 1 < argc) {
            const std::string name = argv[++i];
            if (name == "none") {
                none = true;
            } else if (std::find(kSynthetic.begin(), kSynthetic.end(), name) != kSynthetic.end()) {
                wanted.push_back(name);
            } else {
                std::fprintf(stderr, "stability: no synthetic class '%s' (--list shows them)\n", name.c_str());
                return 2;
            }
        } else {
            rest.push_back(argv[i]);
        }
    }
    if (wanted.empty() && !none) wanted = kSynthetic;
    bench::SweepArgs args = bench::parse_sweep_args(static_cast<int>(rest.size()), rest.data(), "stability.csv", kDefaultSpecs);
    const std::vector<std::string>& specs = args.specs;
    std::vector<fs::path>& files = args.files;
    const std::string& out_path = args.out;
    std::vector<Material> materials = synthetic(wanted);
    try {
        for (const fs::path& f : files) materials.push_back({f.stem().string(), "real: " + f.extension().string(), load(f.string()).brdf});
    } catch (const Error& e) {
        std::fprintf(stderr, "stability: %s\n", e.what());
        return 1;
    }

    const Scene grazing = view_scene(75.0, 88.0), normal = view_scene(0.0, 30.0);
    std::ofstream csv(out_path);
    csv << "material,class,repr,status,bytes,cos_rmse_rel,log_rmse,grazing_ratio,sampler_variance_ratio,bad_values,"
           "eval_pairs_per_s,build_s,flags\n";
    for (const Material& m : materials) {
        for (const std::string& spec : specs) {
            Row r;
            r.material = m.name;
            r.cls = m.cls;
            r.spec = spec;
            std::fprintf(stderr, "%-8s %-36s", m.name.c_str(), spec.c_str());
            try {
                const Trial t = trial(*m.brdf, spec);
                r.bytes = t.bytes;
                r.cos_rel = t.metrics.cos_rmse_rel.mean;
                r.log_rmse = t.metrics.log_rmse.mean;
                r.rate = t.eval_rate;
                r.seconds = t.build_seconds;
                bool poor = false;
                for (const std::string& n : t.notes) {
                    if (n.rfind("fit ", 0) == 0) r.status = n.substr(4, n.find(':') - 4);
                    poor = poor || n.rfind("poor fit", 0) == 0;
                }
                r.bad = bad_values(*t.brdf);
                const double e_normal = scene_error(*m.brdf, *t.brdf, normal, SceneMetric::Image);
                const double e_grazing = scene_error(*m.brdf, *t.brdf, grazing, SceneMetric::Image);
                r.grazing = e_grazing / std::max(e_normal, 1e-6);
                r.sampler = sampler_variance_ratio(*t.brdf, 60.0 * std::numbers::pi / 180.0, 20000, 0.1, 11);
                if (r.status != "ok" && r.status != "converged") r.flags.push_back(r.status);
                if (poor) r.flags.push_back("poor fit");
                if (!(r.cos_rel <= 0.5)) r.flags.push_back("error blow-up");
                if (r.bad) r.flags.push_back("bad values");
                if (r.grazing > 10.0 && e_grazing > 0.05) r.flags.push_back("grazing artefacts");
                // 20,000 samples of a peaked integrand estimate the variance to some 20%: a margin for that.
                if (!(r.sampler <= 1.5)) r.flags.push_back("sampler worse than cosine");
            } catch (const Error& e) {
                r.status = std::string("error: ") + e.what();
                r.flags.push_back("failed");
            }
            std::string flags;
            for (const std::string& f : r.flags) flags += (flags.empty() ? "" : "; ") + f;
            std::fprintf(stderr, " %s cos_rel %s grazing %s sampler %s %s\n", r.status.substr(0, 40).c_str(),
                         num(r.cos_rel).c_str(), num(r.grazing).c_str(), num(r.sampler).c_str(), flags.c_str());
            std::string status = r.status;
            std::replace(status.begin(), status.end(), ',', ';');
            csv << r.material << "," << r.cls << "," << '"' << r.spec << '"' << "," << '"' << status << '"' << ","
                << r.bytes << "," << num(r.cos_rel) << "," << num(r.log_rmse) << "," << num(r.grazing) << ","
                << num(r.sampler) << "," << r.bad << "," << num(r.rate) << "," << num(r.seconds) << "," << '"' << flags
                << '"' << "\n";
            csv.flush();
        }
    }

    std::fprintf(stderr, "wrote %s\n", out_path.c_str());
    return 0;
}
