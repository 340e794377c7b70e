#include "brdfz/repr/spec.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "brdfz/errors.h"

namespace brdfz {
namespace {

std::vector<std::string> split(const std::string& text, char sep) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (;;) {
        const std::size_t end = text.find(sep, start);
        parts.push_back(text.substr(start, end - start));
        if (end == std::string::npos) return parts;
        start = end + 1;
    }
}

}  // namespace

ReprSpec ReprSpec::parse(const std::string& text) {
    ReprSpec spec;
    const std::size_t colon = text.find(':');
    spec.kind_ = text.substr(0, colon);
    if (spec.kind_.empty()) throw SpecError("representation spec '" + text + "': no kind before ':'");
    if (colon == std::string::npos) return spec;
    for (const std::string& part : split(text.substr(colon + 1), ',')) {
        const std::size_t eq = part.find('=');
        if (eq == std::string::npos) {
            if (part.empty() || !spec.positional_.empty() || !spec.options_.empty())
                throw SpecError("representation spec '" + text + "': expected KEY=VALUE, got '" + part + "'");
            spec.positional_ = part;
            continue;
        }
        std::string key = part.substr(0, eq);
        if (key.empty()) throw SpecError("representation spec '" + text + "': empty key in '" + part + "'");
        if (spec.find(key)) throw SpecError("representation spec '" + text + "': '" + key + "' given twice");
        spec.options_.emplace_back(std::move(key), part.substr(eq + 1));
    }
    spec.used_.assign(spec.options_.size(), false);
    return spec;
}

std::string ReprSpec::str() const {
    std::string out = kind_;
    char sep = ':';
    if (!positional_.empty()) {
        out += sep + positional_;
        sep = ',';
    }
    for (const auto& [key, value] : options_) {
        out += sep + key + "=" + value;
        sep = ',';
    }
    return out;
}

void ReprSpec::declare(const std::vector<SpecKey>& keys, bool takes_positional) {
    declared_ = &keys;
    if (!positional_.empty() && !takes_positional) {
        for (const SpecKey& k : keys)
            if (k.name == positional_)
                throw SpecError(kind_ + ": option " + positional_ + " needs a value (" + positional_ + "=...)");
        throw SpecError(kind_ + ": unknown option(s) " + positional_);
    }
    std::string unknown;
    for (const auto& option : options_) {
        bool known = false;
        for (const SpecKey& k : keys) known = known || k.name == option.first;
        if (!known) unknown += (unknown.empty() ? "" : ", ") + option.first;
    }
    if (!unknown.empty()) throw SpecError(kind_ + ": unknown option(s) " + unknown);
}

const std::string* ReprSpec::find(const std::string& key) const {
    if (declared_) {
        bool known = false;
        for (const SpecKey& k : *declared_) known = known || k.name == key;
        if (!known) throw std::logic_error(kind_ + ": the builder reads key '" + key + "', which the kind does not declare");
    }
    for (std::size_t i = 0; i < options_.size(); ++i)
        if (options_[i].first == key) {
            if (i < used_.size()) used_[i] = true;
            return &options_[i].second;
        }
    return nullptr;
}

bool ReprSpec::has(const std::string& key) const { return find(key) != nullptr; }

int ReprSpec::get_int(const std::string& key, int fallback, int min_value, int max_value) const {
    const std::string* value = find(key);
    if (!value) return fallback;
    int parsed = 0;
    const auto [end, ec] = std::from_chars(value->data(), value->data() + value->size(), parsed);
    // A whole number beyond int's range is out of range, not "not an integer".
    const bool too_large = ec == std::errc::result_out_of_range && end == value->data() + value->size();
    if (!too_large && (ec != std::errc() || end != value->data() + value->size()))
        throw SpecError(kind_ + ": " + key + "='" + *value + "' is not an integer");
    if (too_large || parsed < min_value || parsed > max_value)
        throw SpecError(kind_ + ": " + key + "=" + *value + " is outside [" + std::to_string(min_value) + ", " +
                         std::to_string(max_value) + "]");
    return parsed;
}

double ReprSpec::get_double(const std::string& key, double fallback) const {
    const std::string* value = find(key);
    if (!value) return fallback;
    double parsed = 0;
    const auto [end, ec] = std::from_chars(value->data(), value->data() + value->size(), parsed);
    if (ec != std::errc() || end != value->data() + value->size() || !std::isfinite(parsed))
        throw SpecError(kind_ + ": " + key + "='" + *value + "' is not a finite number");
    return parsed;
}

std::string ReprSpec::get_string(const std::string& key, const std::string& fallback) const {
    const std::string* value = find(key);
    return value ? *value : fallback;
}

std::string ReprSpec::get_choice(const std::string& key, const std::string& fallback,
                                 const std::vector<std::string>& choices) const {
    const std::string value = get_string(key, fallback);
    for (const std::string& choice : choices)
        if (value == choice) return value;
    std::string list;
    for (const std::string& choice : choices) list += (list.empty() ? "" : ", ") + choice;
    throw SpecError(kind_ + ": " + key + "='" + value + "' is not one of " + list);
}

std::vector<int> ReprSpec::get_dims(const std::string& key, const std::vector<int>& fallback) const {
    const std::string* value = find(key);
    if (!value) return fallback;
    std::vector<int> dims;
    for (const std::string& part : split(*value, 'x')) {
        int n = 0;
        const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), n);
        if (ec != std::errc() || end != part.data() + part.size() || n < 1)
            throw SpecError(kind_ + ": " + key + "='" + *value + "' is not a list of positive sizes like 45x45x90");
        dims.push_back(n);
    }
    if (dims.size() != fallback.size())
        throw SpecError(kind_ + ": " + key + "='" + *value + "' needs " + std::to_string(fallback.size()) + " sizes");
    return dims;
}

void ReprSpec::finish() const {
    std::string unknown;
    for (std::size_t i = 0; i < options_.size(); ++i)
        if (!used_[i]) unknown += (unknown.empty() ? "" : ", ") + options_[i].first;
    if (!unknown.empty()) throw SpecError(kind_ + ": unknown option(s) " + unknown);
}

}  // namespace brdfz
