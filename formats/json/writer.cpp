#include <cmath>
#include <cstdio>
#include <string>

#include "brdfz/errors.h"
#include "brdfz/formats/model_json.h"
#include "detail/atomic_file.h"

namespace brdfz::model_json {
namespace {

std::string quoted(const std::string& s) {
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
            out += buf;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

// JSON has no NaN or infinity: a non-finite provenance number is written as null.
std::string number(double v) {
    if (!std::isfinite(v)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

}  // namespace

void write(const std::string& path, const AnalyticBrdf& model, const Provenance& provenance) {
    const Model& m = model.model();
    std::string text = "{\n  \"format\": " + quoted(kFormatName) + ",\n  \"version\": " + std::to_string(kVersion) +
                       ",\n  \"model\": " + quoted(m.text()) + ",\n  \"parameters\": {";
    for (std::size_t i = 0; i < m.size(); ++i)
        text += (i ? ",\n    " : "\n    ") + quoted(m.name(i)) + ": " + number(model.params()[i]);
    text += "\n  }";
    if (!provenance.empty()) {
        text += ",\n  \"provenance\": {";
        for (std::size_t i = 0; i < provenance.size(); ++i) {
            const auto& [key, value] = provenance[i];
            text += (i ? ",\n    " : "\n    ") + quoted(key) + ": ";
            text += std::holds_alternative<std::string>(value) ? quoted(std::get<std::string>(value))
                                                                : number(std::get<double>(value));
        }
        text += "\n  }";
    }
    text += "\n}\n";
    detail::AtomicFile file(path);
    file.write(text.data(), text.size());
    file.commit();
}

}  // namespace brdfz::model_json
