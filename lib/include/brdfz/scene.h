// How a scene uses a material: which (wi, wo) pairs it evaluates and how much each contributes to the
// image. A model only has to be good where the scene looks, so errors for budget-driven selection
// (select.h) are measured under this distribution. Scene files (JSON) are documented in
// docs/scene-json.md and read by brdfz/formats/scene_json.h.
//
// A scene is a set of views (pixels): view directions wo relative to the surface normal. Each view is
// lit by directional lights (each a small cone of directions) and an environment (uniform radiance
// over the hemisphere). Its pixel value is L(wo) = Σ_s weight_s · f(wi_s, wo) over the view's samples:
// a light of intensity I (irradiance at normal incidence) contributes I·cosθi/n per sample of its cone,
// the environment E·π/m per cosine-distributed sample. Explicit pairs are views of their own.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brdfz/brdf.h"

namespace brdfz {

struct ViewCone {
    Vec3 axis{0, 0, 1};           // centre of the view directions, relative to the normal
    double max_angle_deg = 90.0;  // views within this angle of the axis (and above the horizon)
    int count = 256;              // view directions drawn (uniform in solid angle inside the cone)
};

struct Light {
    Vec3 direction{0, 0, 1};   // towards the light, relative to the normal
    double spread_deg = 0.0;   // half-angle of the light's cone (0: a point light at infinity)
    double intensity = 1.0;    // irradiance at normal incidence
    int samples = 16;          // directions drawn in the cone (1 when spread is 0)
};

struct Environment {
    double radiance = 0.0;  // uniform over the upper hemisphere; 0: no environment
    int samples = 64;       // cosine-distributed directions per view
};

struct ExplicitPair {
    Vec3 wi, wo;
    double weight = 1.0;
};

struct SceneDescription {
    std::string name;
    std::vector<ViewCone> views;  // empty with explicit pairs only
    std::vector<Light> lights;
    Environment environment;
    std::vector<ExplicitPair> pairs;
    std::uint64_t seed = 1;
};

struct SceneSample {
    Vec3 wi, wo;
    double weight = 0;       // contribution of f(wi, wo) to its view's pixel
    std::uint32_t view = 0;  // index of the view (pixel) it belongs to
};

struct Scene {
    std::string name;
    std::uint32_t views = 0;
    std::vector<SceneSample> samples;  // grouped by view, all above the horizon, weights > 0
};

// Draws the scene's samples (deterministic for a seed). ValueError naming the field for non-finite or
// zero directions, negative intensities or weights, counts outside [1, 1e6], more than 2·10^7 pairs in
// all, a scene with no samples.
Scene build_scene(const SceneDescription& description);

// The default judge of `--metric image` without a scene: a sphere seen from afar (views over the
// whole hemisphere) under a light 45° off the normal and a dim uniform environment.
SceneDescription default_scene();

// How far `approx` is from `reference` in a scene, unitless, the three channels pooled:
//   image: sqrt(Σ_views,c (L_ref − L_approx)² / Σ_views,c L_ref²), the pixels' relative RMS error;
//   cos:   the same over single samples' contributions weight·f, before they are summed into pixels;
//   log:   sqrt(Σ w (ln(1 + f_ref·c) − ln(1 + f_approx·c))² / Σ w) with c = cosθi, w the normalised weights.
enum class SceneMetric { Image, Cos, Log };
SceneMetric parse_scene_metric(const std::string& name);  // "image" | "cos" | "log"
const char* scene_metric_name(SceneMetric metric);
double scene_error(const Brdf& reference, const Brdf& approx, const Scene& scene, SceneMetric metric);

}  // namespace brdfz
