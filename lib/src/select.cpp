#include "brdfz/select.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "brdfz/control.h"
#include "brdfz/errors.h"

namespace brdfz {
namespace {

template <typename Source>
Trial measure(const Source& source, const std::string& spec, const TrialOptions& options) {
    Compressed c = compress(source, spec, options.compress);
    Trial t;
    t.spec = std::move(c.spec);
    t.describe = c.brdf->describe();
    t.bytes = c.brdf->nbytes();
    t.metrics = compare(source, *c.brdf, options.metrics);
    if (options.measure_speed) t.eval_rate = eval_rate(*c.brdf);
    t.build_seconds = c.build_seconds;
    t.notes = std::move(c.notes);
    t.brdf = std::move(c.brdf);
    return t;
}

// The specs whose kind is registered.
std::vector<std::string> registered(std::vector<std::string> specs) {
    std::erase_if(specs,
                  [](const std::string& spec) { return !find_representation_kind(ReprSpec::parse(spec).kind()); });
    return specs;
}

}  // namespace

Trial trial(const Brdf& source, const std::string& spec, const TrialOptions& options) {
    return measure(source, spec, options);
}

Trial trial(const MeasurementSet& source, const std::string& spec, const TrialOptions& options) {
    return measure(source, spec, options);
}

std::vector<std::string> benchmark_specs() {
    return registered({
        "tabular:res=90x90x180",  // the MERL grid in float32: the baseline
        "tabular:res=45x45x90",          "tabular:res=45x45x90,dtype=f16",   "tabular:res=45x45x90,dtype=u8log",
        "tabular:res=32x32x64,dtype=f16", "tabular:res=32x32x64,dtype=u8log", "tabular:res=16x16x32,dtype=u8log",
        "bivariate:res=90x90",           "bivariate:res=90x90,dtype=u8log",  "bivariate:res=32x32,dtype=f16",
        "svd:rank=1,space=log",          "svd:rank=2,space=log",             "svd:rank=4,space=log",
        "svd:rank=8,space=log",          "svd:rank=4,space=cos",             "nmf:rank=1",
        "nmf:rank=2",                    "nmf:rank=4",                       "analytic:lambert+ggx",
        "analytic:lambert+ggx+ggx",      "analytic:lambert+beckmann",
    });
}

std::vector<std::string> default_candidates() {
    // In order of bytes for three channels (the comments), so the first within budget is the smallest.
    // The symmetry=none ones keep φd over [0, 2π) for non-reciprocal data (RGL files), which a
    // reciprocal grid holds as the mean of the two sides; the symmetry=bilateral ones keep it in half
    // the bins, φd folded by the mirror that isotropic data have.
    return registered({
        "analytic:lambert+ggx",                             // 64
        "analytic:lambert+ggx+ggx",                         // 104
        // RGL-EPFL files only, in their own parameterisation, int8 factors (rgl_svd; sizes at the files' 8 θi
        // slices to 80°, fewer bytes at 7), chosen on the tune half of the shared RGL files (below): rank 5
        // is the largest within Neural-BRDF's 2,700 B (there closer than the 2,544 B svd on 4 of 7 files, worst
        // 4.57 % against 8.35 %).
        "rgl_svd:rank=5,dtype=i8",  // 2,414
        // At most Neural-BRDF's 2,700 B, for the error over directions.
        "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16",  // 2,544
        // Each of the three settings for RGL files over directions again on a θh axis warped by the source's
        // own specular peak (hwarp=auto), after the square-root one: the warp helps most sources with a
        // sharp peak but not every one, so both are tried. Same bytes, so --auto takes the warped one only
        // where the plain one misses the budget, and --max-bytes the closer of the two.
        "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16,hwarp=auto",  // 2,544
        "bivariate:res=32x32,dtype=u8log",                  // 3,144
        // rgl_svd: rank 8, the smallest within 2 % on every tune file (worst 1.61 %).
        "rgl_svd:rank=8,dtype=i8",  // 3,536
        // At most 4 KB, chosen among 14 settings on the tune half of the shared RGL files (acrylic_felt_white,
        // cardboard, cc_nothern_aurora, colodur_azure_4e, irid_flake_paint2, paper_white, satin_rosaline) by
        // files within 2 % over directions, then median: there 4 of 7, median 1.56 %; on the other seven
        // 0 of 7, median 3.41 % (the 2,544 B one 6.61 %).
        "svd:rank=6,space=cos,colour=shared,res=32x22x13,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16",  // 3,888
        "svd:rank=6,space=cos,colour=shared,res=32x22x13,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16,hwarp=auto",  // 3,888
        // rgl_svd: rank 9, the largest within 4 KB; then a ladder in int8 up to rank 22, beyond which the
        // codes' rounding bounds the error (worst on the tune half 0.48 %), and in float16 at rank 16.
        "rgl_svd:rank=9,dtype=i8",   // 3,910
        "rgl_svd:rank=12,dtype=i8",  // 5,032
        "rgl_svd:rank=16,dtype=i8",  // 6,528
        "rgl_svd:rank=22,dtype=i8",  // 8,772
        "rgl_svd:rank=16",           // 11,808
        // At most 16 KB for the error over directions (with the 14,560 B one below); the second with the
        // θh rows and rank of sharp specular spikes (chm_mint).
        "svd:rank=10,space=cos,colour=shared,res=50x40x14,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16",  // 12,320
        "svd:rank=10,space=cos,colour=shared,res=50x40x14,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16,hwarp=auto",  // 12,320
        "svd:rank=14,space=cos,colour=shared,res=128x28x12,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16",  // 13,160
        "svd:rank=4,space=cos,res=32x16x16",                // 13,824
        "svd:rank=6,space=cos,colour=shared,res=90x32x16",  // 14,520
        "svd:rank=10,space=cos,colour=shared,res=50x24x28,dwarp=0.9,fit=lsq,weight=solid,symmetry=none,dtype=f16",  // 14,560
        // Reciprocal sources. On the size benchmark's four RGL materials, which are not, it holds the mean of
        // f(wi, wo) and f(wo, wi), 1.5–9.7 % off; the same spec with symmetry=none is within 2 % on each.
        // default_candidates(source) keeps φd whole in this one and those below for such sources.
        "svd:rank=8,space=cos,colour=shared,res=64x48x18,dwarp=0.9,fit=lsq,dtype=f16",  // 14,944
        // rgl_svd in float16 at rank 22, the largest within 16 KB at 8 slices (14,624 B at 7).
        "rgl_svd:rank=22",  // 16,032
        // Reciprocal sources, without a factorisation to build (on those four as the spec above).
        "tabular:res=24x28x8,dtype=u8log,filter=lsq,dwarp=0.8",  // 16,200
        "tabular:res=16x16x32,dtype=u8log",                 // 24,648
        "tabular:res=32x32x64,dtype=u8log",                 // 196,680
        "tabular:res=45x45x90,dtype=u8log",                 // 546,822
        "tabular:res=45x45x90,dtype=f16",                   // 1,093,572
        "tabular:res=48x48x180,dtype=u8log,symmetry=none",  // 1,244,232
        "tabular:res=90x90x180,dtype=u8log",                // 4,374,072
        // chm_mint's specular spike (θh < 2°) wants 360 θh bins.
        "tabular:res=360x45x90,dtype=f16,symmetry=bilateral",  // 8,748,072
        "tabular:res=90x90x180",                            // 17,496,000
        "tabular:res=90x90x360,dtype=f16,symmetry=none",    // 17,496,072
        "tabular:res=90x90x360,symmetry=none",              // 34,992,000
    });
}

bool is_reciprocal(const Brdf& source, const MetricOptions& options) {
    return reciprocity_error(source, options).cos_rmse_rel.mean <= kReciprocityThreshold;
}

std::vector<std::string> keep_phi_d_whole(std::vector<std::string> specs) {
    // Whether the kind's symmetry= takes bilateral: its help lists the choices before the ':'.
    const auto takes_bilateral = [](const std::string& kind) {
        const ReprKind* k = find_representation_kind(kind);
        if (!k) return false;
        const auto key = std::ranges::find(k->keys, std::string("symmetry"), &SpecKey::name);
        if (key == k->keys.end()) return false;
        std::string choices = key->help.substr(0, key->help.find(':'));
        choices.insert(choices.begin(), '|');
        return (choices += '|').find("|bilateral|") != std::string::npos;
    };
    const std::string folded = "symmetry=reciprocal";
    for (std::string& spec : specs) {
        const ReprSpec parsed = ReprSpec::parse(spec);
        if (!takes_bilateral(parsed.kind())) continue;
        if (!parsed.has("symmetry"))
            spec += (spec.find(':') == std::string::npos ? ":" : ",") + std::string("symmetry=bilateral");
        else if (parsed.get_string("symmetry", "") == "reciprocal")
            spec.replace(spec.find(folded), folded.size(), "symmetry=bilateral");
    }
    return specs;
}

std::vector<std::string> default_candidates(const Brdf& source, const MetricOptions& options) {
    std::vector<std::string> out;
    for (const std::string& spec : default_candidates()) {
        const ReprKind* kind = find_representation_kind(ReprSpec::parse(spec).kind());
        if (!kind->applies || kind->applies(source)) out.push_back(spec);
    }
    return is_reciprocal(source, options) ? out : keep_phi_d_whole(std::move(out));
}

Selection select_representation(const Brdf& source, const SelectOptions& options) {
    if (!options.max_error && !options.max_bytes) throw ValueError("select: give an error budget, a size budget or both");
    if (options.max_error && !(std::isfinite(*options.max_error) && *options.max_error > 0.0))
        throw ValueError("select: the error budget must be a finite number > 0");
    if (options.max_bytes && *options.max_bytes == 0) throw ValueError("select: the size budget must be at least 1 byte");
    const std::vector<std::string> candidates =
        options.candidates.empty() ? default_candidates(source, options.trial.metrics) : options.candidates;
    const std::optional<Scene> judge =
        options.scene ? options.scene
                      : options.metric == SceneMetric::Image ? std::optional<Scene>(build_scene(default_scene())) : std::nullopt;
    for (const std::string& spec : candidates) check_spec(spec);
    // A thread count beyond the bound is the caller's mistake, not every candidate's failure.
    resolve_threads(options.trial.compress.threads);
    resolve_threads(options.trial.metrics.threads);
    // Without an error budget the choice is the most accurate within the size budget, known only when
    // the candidates within it have all been measured: until then the best so far is kept.
    const bool most_accurate = !options.max_error;
    Selection out;
    for (const std::string& spec : candidates) {
        poll_stop();
        Candidate c;
        bool larger = false;
        try {
            c.trial = trial(source, spec, options.trial);
            if (judge)
                c.error = scene_error(source, *c.trial.brdf, *judge, options.metric);
            else
                c.error = options.metric == SceneMetric::Cos ? c.trial.metrics.cos_rmse_rel.mean : c.trial.metrics.log_rmse.mean;
            char buf[128];
            larger = options.max_bytes && c.trial.bytes > *options.max_bytes;
            if (!std::isfinite(c.error)) {
                c.reason = "error is not finite";
            } else if (larger) {
                std::snprintf(buf, sizeof buf, "%zu bytes > size budget %llu", c.trial.bytes,
                              static_cast<unsigned long long>(*options.max_bytes));
                c.reason = buf;
            } else if (options.max_error && c.error > *options.max_error) {
                std::snprintf(buf, sizeof buf, "error %.4g > budget %.4g", c.error, *options.max_error);
                c.reason = buf;
            } else if (most_accurate) {
                const Candidate* best = out.best();
                if (best && best->error <= c.error) {
                    std::snprintf(buf, sizeof buf, "error %.4g, not below %.4g of %s", c.error, best->error, best->trial.spec.c_str());
                    c.reason = buf;
                } else {
                    c.accepted = true;
                    c.reason = "the most accurate within the size budget so far";
                }
            } else {
                c.accepted = true;
                c.reason = "meets the budget";
            }
        } catch (const SpecError&) {
            throw;
        } catch (const Error& e) {
            c.trial.spec = spec;
            c.error = std::nan("");
            c.reason = std::string("failed: ") + e.what();
        }
        if (!c.accepted) c.trial.brdf.reset();  // only the chosen one is kept in memory
        if (c.accepted && most_accurate && out.best()) {
            Candidate& before = out.tried[static_cast<std::size_t>(out.chosen)];
            before.accepted = false;
            before.trial.brdf.reset();
            char buf[128];
            std::snprintf(buf, sizeof buf, "error %.4g, above %.4g of %s", before.error, c.error, c.trial.spec.c_str());
            before.reason = buf;
        }
        out.tried.push_back(std::move(c));
        if (out.tried.back().accepted) out.chosen = static_cast<int>(out.tried.size()) - 1;
        if (options.on_candidate) options.on_candidate(out.tried.back());
        if ((out.tried.back().accepted && !most_accurate) || larger) break;
    }
    if (most_accurate && out.best()) out.tried[static_cast<std::size_t>(out.chosen)].reason = "the most accurate within the size budget";
    return out;
}

namespace {

// CSV field: quoted when it holds a comma, a quote or a line break.
std::string field(const std::string& s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

}  // namespace

std::string sweep_csv_row(const std::string& material, const std::string& format, const std::string& spec,
                          std::uintmax_t input_bytes, const Trial* trial, const std::string& error) {
    std::string row = field(material) + "," + field(format) + "," + field(spec) + ",";
    if (!trial) return row + ",," + std::to_string(input_bytes) + ",,,,,,,," + field("error: " + error);
    const Trial& t = *trial;
    std::string status = "ok";
    for (const std::string& n : t.notes) status += "; " + n;
    return row + field(t.describe) + "," + std::to_string(t.bytes) + "," + std::to_string(input_bytes) + "," +
           num(static_cast<double>(input_bytes) / static_cast<double>(t.bytes)) + "," + num(t.metrics.cos_rmse.mean) +
           "," + num(t.metrics.cos_rmse_rel.mean) + "," + num(t.metrics.log_rmse.mean) + "," +
           num(t.metrics.cbrt_rmse.mean) + "," + num(t.eval_rate) + "," + num(t.build_seconds) + "," + field(status);
}

std::string sweep_csv_directions(const Metrics* over_directions) {
    if (!over_directions) return ",,,,";
    std::string cells;
    for (const PerChannel* p : {&over_directions->cos_rmse, &over_directions->cos_rmse_rel, &over_directions->log_rmse,
                                &over_directions->cbrt_rmse})
        (cells += ',') += num(p->mean);
    return cells;
}

}  // namespace brdfz
