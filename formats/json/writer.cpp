#include <sstream>
#include <string>

#include "brdfz/formats/json_writer.h"
#include "brdfz/formats/model_json.h"
#include "detail/atomic_file.h"

namespace brdfz::model_json {

void write(const std::string& path, const AnalyticBrdf& model, const Provenance& provenance) {
    const Model& m = model.model();
    std::ostringstream text;
    json::Writer j(text, 2);
    j.begin_object();
    j.key("format").value(kFormatName);
    j.key("version").value(std::size_t{kVersion});
    j.key("model").value(m.text());
    j.key("parameters").begin_object();
    for (std::size_t i = 0; i < m.size(); ++i) j.key(m.name(i)).value(model.params()[i]);
    j.end_object();
    if (!provenance.empty()) {
        j.key("provenance").begin_object();
        for (const auto& [key, value] : provenance) {
            j.key(key);
            if (const auto* s = std::get_if<std::string>(&value))
                j.value(*s);
            else
                j.value(std::get<double>(value));
        }
        j.end_object();
    }
    j.end_object();
    text << "\n";
    const std::string bytes = text.str();
    detail::AtomicFile file(path);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

}  // namespace brdfz::model_json
