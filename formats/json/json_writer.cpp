#include "brdfz/formats/json_writer.h"

#include <cmath>
#include <cstdio>

namespace brdfz::json {

void Writer::separate() {
    if (after_key_) {
        after_key_ = false;
        return;
    }
    const bool top = first_.size() == 1;
    if (!first_.back()) os_ << ",";
    if (indent_ > 0 && !top)
        os_ << "\n" << std::string(static_cast<std::size_t>(indent_) * (first_.size() - 1), ' ');
    else if (!first_.back())
        os_ << " ";
    first_.back() = false;
}

void Writer::close(char bracket) {
    const bool empty = first_.back();
    first_.pop_back();
    if (indent_ > 0 && !empty) os_ << "\n" << std::string(static_cast<std::size_t>(indent_) * (first_.size() - 1), ' ');
    os_ << bracket;
}

Writer& Writer::begin_object() {
    separate();
    os_ << "{";
    first_.push_back(true);
    return *this;
}
Writer& Writer::end_object() {
    close('}');
    return *this;
}
Writer& Writer::begin_array() {
    separate();
    os_ << "[";
    first_.push_back(true);
    return *this;
}
Writer& Writer::end_array() {
    close(']');
    return *this;
}
Writer& Writer::key(const std::string& k) {
    value(k);
    os_ << ": ";
    after_key_ = true;
    return *this;
}
Writer& Writer::value(double v) {
    separate();
    if (!std::isfinite(v)) {
        os_ << "null";
        return *this;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    os_ << buf;
    return *this;
}
Writer& Writer::value(std::size_t v) {
    separate();
    os_ << v;
    return *this;
}
Writer& Writer::value(bool v) {
    separate();
    os_ << (v ? "true" : "false");
    return *this;
}
Writer& Writer::value(const char* v) { return value(std::string(v)); }
Writer& Writer::value(const std::string& v) {
    separate();
    os_ << '"';
    for (const char c : v) {
        if (c == '"' || c == '\\') {
            os_ << '\\' << c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
            os_ << buf;
        } else {
            os_ << c;
        }
    }
    os_ << '"';
    return *this;
}

}  // namespace brdfz::json
