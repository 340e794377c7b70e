#include "brdfz/scene.h"

#include <cmath>
#include <numbers>
#include <random>

#include "brdfz/errors.h"

namespace brdfz {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr int kMaxCount = 1000000;
constexpr double kMaxSamples = 2e7;  // pairs in all: a scene is a judge, not a renderer (memory ~1 GB)

Vec3 checked_direction(const Vec3& v, const std::string& where) {
    const double len = length(v);
    if (!std::isfinite(len) || len == 0.0) throw ValueError("scene: " + where + " must be a finite non-zero vector");
    return (1.0 / len) * v;
}

void check_count(int n, const std::string& where) {
    if (n < 1 || n > kMaxCount)
        throw ValueError("scene: " + where + " = " + std::to_string(n) + " is outside [1, " + std::to_string(kMaxCount) + "]");
}

void check_non_negative(double v, const std::string& where) {
    if (!(std::isfinite(v) && v >= 0.0)) throw ValueError("scene: " + where + " must be finite and >= 0");
}

// An orthonormal frame whose third axis is `n`.
void frame_of(const Vec3& n, Vec3& t, Vec3& b) {
    const Vec3 a = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 c{a.y * n.z - a.z * n.y, a.z * n.x - a.x * n.z, a.x * n.y - a.y * n.x};
    t = normalize(c);
    b = {n.y * t.z - n.z * t.y, n.z * t.x - n.x * t.z, n.x * t.y - n.y * t.x};
}

// Uniform in solid angle inside the cone of half-angle `half` around `axis`.
Vec3 in_cone(const Vec3& axis, double half, double u1, double u2) {
    const double cos_t = 1.0 - u1 * (1.0 - std::cos(half));
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
    const double phi = 2.0 * std::numbers::pi * u2;
    Vec3 t, b;
    frame_of(axis, t, b);
    return normalize(sin_t * std::cos(phi) * t + sin_t * std::sin(phi) * b + cos_t * axis);
}

}  // namespace

SceneMetric parse_scene_metric(const std::string& name) {
    if (name == "image") return SceneMetric::Image;
    if (name == "cos") return SceneMetric::Cos;
    if (name == "log") return SceneMetric::Log;
    throw ValueError("unknown metric '" + name + "' (expected image, cos or log)");
}

const char* scene_metric_name(SceneMetric metric) {
    switch (metric) {
        case SceneMetric::Image: return "image";
        case SceneMetric::Cos: return "cos";
        case SceneMetric::Log: return "log";
    }
    return "?";
}

Scene build_scene(const SceneDescription& d) {
    Scene scene;
    scene.name = d.name;
    std::mt19937_64 rng(d.seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);

    // The light samples do not depend on the view: drawn once, shared by every view.
    struct Incident {
        Vec3 wi;
        double weight;  // before the cosine, which the view loop applies
        bool cosine;    // weight still needs cosθi (lights) or already includes it (environment)
    };
    std::vector<Incident> incident;
    for (std::size_t l = 0; l < d.lights.size(); ++l) {
        const Light& light = d.lights[l];
        const std::string where = "lights[" + std::to_string(l) + "]";
        const Vec3 dir = checked_direction(light.direction, where + ".direction");
        check_non_negative(light.intensity, where + ".intensity");
        check_non_negative(light.spread_deg, where + ".spread_deg");
        if (light.spread_deg > 90.0) throw ValueError("scene: " + where + ".spread_deg must be at most 90");
        const int n = light.spread_deg > 0.0 ? light.samples : 1;
        check_count(n, where + ".samples");
        for (int k = 0; k < n; ++k) {
            const Vec3 wi = light.spread_deg > 0.0 ? in_cone(dir, light.spread_deg * kDeg, u01(rng), u01(rng)) : dir;
            incident.push_back({wi, light.intensity / n, true});
        }
    }
    if (d.environment.radiance != 0.0) {
        check_non_negative(d.environment.radiance, "environment.radiance");
        check_count(d.environment.samples, "environment.samples");
        // Stratified in (u1, u2) rows so small sample counts still cover the hemisphere evenly.
        const int m = d.environment.samples;
        const int rows = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(m))));
        for (int k = 0; k < m; ++k) {
            const double u1 = (k % rows + u01(rng)) / rows;
            const double u2 = u01(rng);
            incident.push_back({cosine_hemisphere(u1, u2), d.environment.radiance * std::numbers::pi / m, false});
        }
    }

    double total = static_cast<double>(d.pairs.size());
    for (const ViewCone& cone : d.views) total += static_cast<double>(std::max(cone.count, 0)) * static_cast<double>(incident.size());
    if (total > kMaxSamples)
        throw ValueError("scene: views x (light and environment samples) asks for " + std::to_string(total) +
                         " direction pairs, more than " + std::to_string(static_cast<long long>(kMaxSamples)));
    for (std::size_t v = 0; v < d.views.size(); ++v) {
        const ViewCone& cone = d.views[v];
        const std::string where = "views[" + std::to_string(v) + "]";
        const Vec3 axis = checked_direction(cone.axis, where + ".axis");
        if (!(cone.max_angle_deg > 0.0 && cone.max_angle_deg <= 180.0))
            throw ValueError("scene: " + where + ".max_angle_deg must be in (0, 180]");
        check_count(cone.count, where + ".count");
        if (incident.empty()) throw ValueError("scene: views need lights or an environment to be seen by");
        for (int k = 0; k < cone.count; ++k) {
            // Views below the horizon see nothing of this surface: redrawn, within a bound.
            Vec3 wo;
            int tries = 0;
            do {
                wo = in_cone(axis, cone.max_angle_deg * kDeg, u01(rng), u01(rng));
            } while (wo.z <= 1e-6 && ++tries < 64);
            if (wo.z <= 1e-6) throw ValueError("scene: " + where + " lies below the horizon");
            bool any = false;
            for (const Incident& in : incident) {
                if (in.wi.z <= 0.0) continue;
                const double w = in.cosine ? in.weight * in.wi.z : in.weight;
                if (w <= 0.0) continue;
                scene.samples.push_back({in.wi, wo, w, scene.views});
                any = true;
            }
            if (any) ++scene.views;
        }
    }
    for (std::size_t p = 0; p < d.pairs.size(); ++p) {
        const ExplicitPair& pair = d.pairs[p];
        const std::string where = "pairs[" + std::to_string(p) + "]";
        const Vec3 wi = checked_direction(pair.wi, where + ".wi");
        const Vec3 wo = checked_direction(pair.wo, where + ".wo");
        check_non_negative(pair.weight, where + ".weight");
        if (wi.z <= 0.0 || wo.z <= 0.0) throw ValueError("scene: " + where + " has a direction below the horizon");
        if (pair.weight == 0.0) continue;
        scene.samples.push_back({wi, wo, pair.weight, scene.views++});
    }
    if (scene.samples.empty()) throw ValueError("scene '" + d.name + "': no direction pair above the horizon with weight > 0");
    return scene;
}

SceneDescription default_scene() {
    SceneDescription d;
    d.name = "default: sphere, light at 45 degrees, dim environment";
    d.views.push_back(ViewCone{{0, 0, 1}, 90.0, 512});
    d.lights.push_back(Light{normalize(Vec3{1, 0, 1}), 2.0, 1.0, 8});
    d.environment = Environment{0.1, 64};
    return d;
}

double scene_error(const Brdf& reference, const Brdf& approx, const Scene& scene, SceneMetric metric) {
    const std::size_t n = scene.samples.size();
    std::vector<Vec3> wi(n), wo(n);
    for (std::size_t k = 0; k < n; ++k) {
        wi[k] = scene.samples[k].wi;
        wo[k] = scene.samples[k].wo;
    }
    std::vector<Rgb> ref(n), app(n);
    reference.eval(wi, wo, ref);
    approx.eval(wi, wo, app);
    const auto value = [](double v) { return std::isfinite(v) ? v : 0.0; };

    double err[3] = {}, norm[3] = {};
    if (metric == SceneMetric::Image) {
        std::vector<Rgb> pix_ref(scene.views), pix_app(scene.views);
        for (std::size_t k = 0; k < n; ++k)
            for (int c = 0; c < 3; ++c) {
                pix_ref[scene.samples[k].view][c] += scene.samples[k].weight * value(ref[k][c]);
                pix_app[scene.samples[k].view][c] += scene.samples[k].weight * value(app[k][c]);
            }
        for (std::uint32_t v = 0; v < scene.views; ++v)
            for (int c = 0; c < 3; ++c) {
                err[c] += (pix_ref[v][c] - pix_app[v][c]) * (pix_ref[v][c] - pix_app[v][c]);
                norm[c] += pix_ref[v][c] * pix_ref[v][c];
            }
    } else {
        for (std::size_t k = 0; k < n; ++k) {
            const SceneSample& s = scene.samples[k];
            for (int c = 0; c < 3; ++c) {
                const double r = value(ref[k][c]), a = value(app[k][c]);
                if (metric == SceneMetric::Cos) {
                    err[c] += s.weight * s.weight * (r - a) * (r - a);
                    norm[c] += s.weight * s.weight * r * r;
                } else {
                    const double d = std::log1p(std::max(r, 0.0) * s.wi.z) - std::log1p(std::max(a, 0.0) * s.wi.z);
                    err[c] += s.weight * d * d;
                    norm[c] += s.weight;
                }
            }
        }
    }
    // Channels pooled, so a channel the reference barely has (a gold's blue) cannot dominate.
    const double e = err[0] + err[1] + err[2], m = norm[0] + norm[1] + norm[2];
    return m > 0.0 ? std::sqrt(e / m) : (e > 0.0 ? 1.0 : 0.0);
}

}  // namespace brdfz
