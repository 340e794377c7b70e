// The analytic model file schema (docs/model-json.md) on top of the strict JSON parser.
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/model_json.h"
#include "parse.h"

namespace brdfz::model_json {

using json::Value;
using json::kind_name;

AnalyticBrdf read(const std::string& path) {
    const Value doc = json::parse_file(path, kMaxFileBytes, "a model file");
    auto bad = [&](const std::string& why) -> FormatError { return FormatError(path, why); };
    if (doc.kind != Value::Kind::Object) throw bad("expected a JSON object at the top level");
    for (const std::string& k : doc.keys)
        if (k != "format" && k != "version" && k != "model" && k != "parameters" && k != "provenance")
            throw bad("unknown member \"" + k + "\"");
    auto require = [&](const char* key, Value::Kind kind) -> const Value& {
        const Value* v = doc.member(key);
        if (!v) throw bad(std::string("missing member \"") + key + "\"");
        if (v->kind != kind)
            throw bad(std::string("member \"") + key + "\" must be " + kind_name(kind) + ", not " + kind_name(v->kind));
        return *v;
    };
    if (require("format", Value::Kind::String).string != kFormatName)
        throw bad(std::string("not an analytic model file (\"format\" is not \"") + kFormatName + "\")");
    const double version = require("version", Value::Kind::Number).number;
    if (version != kVersion)
        throw bad("unsupported version " + std::to_string(version) + " (this build reads version " +
                  std::to_string(kVersion) + ")");
    Model model = [&] {
        try {
            return Model::parse(require("model", Value::Kind::String).string);
        } catch (const ValueError& e) {
            throw bad(e.what());
        }
    }();
    const Value& params = require("parameters", Value::Kind::Object);
    if (const Value* p = doc.member("provenance"); p && p->kind != Value::Kind::Object)
        throw bad(std::string("member \"provenance\" must be an object, not ") + kind_name(p->kind));

    std::vector<double> values(model.size());
    std::vector<bool> seen(model.size(), false);
    for (std::size_t i = 0; i < params.keys.size(); ++i) {
        const std::size_t k = model.find(params.keys[i]);
        if (k == model.size())
            throw bad("unknown parameter \"" + params.keys[i] + "\" for model " + model.text());
        if (params.items[i].kind != Value::Kind::Number)
            throw bad("parameter \"" + params.keys[i] + "\" must be a number, not " + kind_name(params.items[i].kind));
        values[k] = params.items[i].number;
        seen[k] = true;
    }
    for (std::size_t k = 0; k < model.size(); ++k)
        if (!seen[k]) throw bad("missing parameter \"" + model.name(k) + "\"");
    try {
        return AnalyticBrdf(std::move(model), std::move(values));
    } catch (const ValueError& e) {
        throw bad(e.what());
    }
}

}  // namespace brdfz::model_json
