// The scene file schema (docs/scene-json.md) on top of the strict JSON parser.
#include <cmath>
#include <initializer_list>
#include <string>

#include "brdfz/errors.h"
#include "brdfz/formats/scene_json.h"
#include "parse.h"

namespace brdfz::scene_json {
namespace {

using json::Value;

class Reader {
public:
    explicit Reader(std::string path) : path_(std::move(path)) {}

    [[noreturn]] void fail(const std::string& where, const std::string& why) const {
        throw FormatError(path_, where + ": " + why);
    }

    // Rejects members outside `known`, so a misspelt key is an error rather than a silent default.
    void only(const Value& object, const std::string& where, std::initializer_list<const char*> known) const {
        if (object.kind != Value::Kind::Object) fail(where, std::string("must be an object, not ") + json::kind_name(object.kind));
        for (const std::string& k : object.keys) {
            bool ok = false;
            for (const char* name : known) ok = ok || k == name;
            if (!ok) fail(where, "unknown member \"" + k + "\"");
        }
    }

    const Value* get(const Value& object, const char* key, Value::Kind kind, const std::string& where) const {
        const Value* v = object.member(key);
        if (v && v->kind != kind)
            fail(where + "." + key, std::string("must be ") + json::kind_name(kind) + ", not " + json::kind_name(v->kind));
        return v;
    }

    double number(const Value& object, const char* key, double fallback, const std::string& where) const {
        const Value* v = get(object, key, Value::Kind::Number, where);
        return v ? v->number : fallback;
    }

    int count(const Value& object, const char* key, int fallback, const std::string& where) const {
        const double v = number(object, key, fallback, where);
        // Range first: casting a double beyond long long's range is undefined (the fuzzer's 4e107 seed).
        if (!(v >= 0 && v <= 1e9) || v != std::floor(v)) fail(where + "." + key, "must be a whole number");
        return static_cast<int>(v);
    }

    Vec3 vector(const Value& object, const char* key, Vec3 fallback, const std::string& where) const {
        const Value* v = get(object, key, Value::Kind::Array, where);
        if (!v) return fallback;
        if (v->items.size() != 3) fail(where + "." + key, "must have 3 numbers");
        double xyz[3];
        for (int i = 0; i < 3; ++i) {
            if (v->items[i].kind != Value::Kind::Number) fail(where + "." + key, "must have 3 numbers");
            xyz[i] = v->items[i].number;
        }
        return {xyz[0], xyz[1], xyz[2]};
    }

    const std::vector<Value>* array(const Value& object, const char* key, const std::string& where) const {
        const Value* v = get(object, key, Value::Kind::Array, where);
        return v ? &v->items : nullptr;
    }

private:
    std::string path_;
};

}  // namespace

SceneDescription read(const std::string& path) {
    const Value doc = json::parse_file(path, kMaxFileBytes, "a scene file");
    const Reader r(path);
    r.only(doc, "scene", {"format", "version", "name", "seed", "views", "lights", "environment", "pairs"});
    const Value* format = r.get(doc, "format", Value::Kind::String, "scene");
    if (!format || format->string != kFormatName)
        r.fail("scene", std::string("not a scene file (\"format\" is not \"") + kFormatName + "\")");
    if (r.number(doc, "version", 0, "scene") != kVersion)
        r.fail("scene", "unsupported version (this build reads version " + std::to_string(kVersion) + ")");

    SceneDescription d;
    if (const Value* name = r.get(doc, "name", Value::Kind::String, "scene")) d.name = name->string;
    d.seed = static_cast<std::uint64_t>(r.count(doc, "seed", 1, "scene"));
    if (const auto* views = r.array(doc, "views", "scene"))
        for (std::size_t i = 0; i < views->size(); ++i) {
            const std::string where = "views[" + std::to_string(i) + "]";
            const Value& v = (*views)[i];
            r.only(v, where, {"axis", "max_angle_deg", "count"});
            ViewCone cone;
            cone.axis = r.vector(v, "axis", cone.axis, where);
            cone.max_angle_deg = r.number(v, "max_angle_deg", cone.max_angle_deg, where);
            cone.count = r.count(v, "count", cone.count, where);
            d.views.push_back(cone);
        }
    if (const auto* lights = r.array(doc, "lights", "scene"))
        for (std::size_t i = 0; i < lights->size(); ++i) {
            const std::string where = "lights[" + std::to_string(i) + "]";
            const Value& v = (*lights)[i];
            r.only(v, where, {"direction", "spread_deg", "intensity", "samples"});
            Light light;
            light.direction = r.vector(v, "direction", light.direction, where);
            light.spread_deg = r.number(v, "spread_deg", light.spread_deg, where);
            light.intensity = r.number(v, "intensity", light.intensity, where);
            light.samples = r.count(v, "samples", light.samples, where);
            d.lights.push_back(light);
        }
    if (const Value* env = r.get(doc, "environment", Value::Kind::Object, "scene")) {
        r.only(*env, "environment", {"radiance", "samples"});
        d.environment.radiance = r.number(*env, "radiance", 0.0, "environment");
        d.environment.samples = r.count(*env, "samples", d.environment.samples, "environment");
    }
    if (const auto* pairs = r.array(doc, "pairs", "scene"))
        for (std::size_t i = 0; i < pairs->size(); ++i) {
            const std::string where = "pairs[" + std::to_string(i) + "]";
            const Value& v = (*pairs)[i];
            r.only(v, where, {"wi", "wo", "weight"});
            if (!v.member("wi") || !v.member("wo")) r.fail(where, "needs \"wi\" and \"wo\"");
            d.pairs.push_back({r.vector(v, "wi", {}, where), r.vector(v, "wo", {}, where), r.number(v, "weight", 1.0, where)});
        }
    return d;
}

Scene load(const std::string& path) {
    const SceneDescription d = read(path);
    try {
        return build_scene(d);
    } catch (const ValueError& e) {
        throw ValueError(path + ": " + e.what());
    }
}

}  // namespace brdfz::scene_json
