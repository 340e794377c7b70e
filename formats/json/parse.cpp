#include "parse.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "brdfz/errors.h"

namespace brdfz::json {

const char* kind_name(Value::Kind k) {
    switch (k) {
        case Value::Kind::Null: return "null";
        case Value::Kind::Bool: return "a boolean";
        case Value::Kind::Number: return "a number";
        case Value::Kind::String: return "a string";
        case Value::Kind::Array: return "an array";
        case Value::Kind::Object: return "an object";
    }
    return "?";
}

namespace {

class Parser {
public:
    Parser(const std::string& path, const std::string& text) : path_(path), text_(text) {}

    Value document() {
        Value v = value(0);
        skip_space();
        if (pos_ != text_.size()) fail("unexpected text after the JSON value");
        return v;
    }

    [[noreturn]] void fail(const std::string& what) const {
        std::size_t line = 1, column = 1;
        for (std::size_t i = 0; i < pos_ && i < text_.size(); ++i) {
            if (text_[i] == '\n') {
                ++line;
                column = 1;
            } else {
                ++column;
            }
        }
        throw FormatError(path_, "line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + what);
    }

private:
    static constexpr int kMaxDepth = 16;

    void skip_space() {
        while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\n' || text_[pos_] == '\r'))
            ++pos_;
    }
    bool at(char c) const { return pos_ < text_.size() && text_[pos_] == c; }
    void expect(char c) {
        skip_space();
        if (!at(c)) fail(std::string("expected '") + c + "'");
        ++pos_;
    }
    bool literal(const char* word) {
        const std::string w(word);
        if (text_.compare(pos_, w.size(), w) != 0) return false;
        pos_ += w.size();
        return true;
    }

    Value value(int depth) {
        if (depth > kMaxDepth) fail("nested deeper than " + std::to_string(kMaxDepth) + " levels");
        skip_space();
        Value v;
        if (pos_ >= text_.size()) fail("unexpected end of file");
        const char c = text_[pos_];
        if (c == '{') {
            v.kind = Value::Kind::Object;
            ++pos_;
            skip_space();
            if (at('}')) {
                ++pos_;
            } else {
                while (true) {
                    skip_space();
                    if (!at('"')) fail("expected a string key");
                    std::string key = string();
                    for (const std::string& k : v.keys)
                        if (k == key) fail("duplicate key \"" + key + "\"");
                    expect(':');
                    v.keys.push_back(std::move(key));
                    v.items.push_back(value(depth + 1));
                    skip_space();
                    if (at(',')) {
                        ++pos_;
                        continue;
                    }
                    expect('}');
                    break;
                }
            }
        } else if (c == '[') {
            v.kind = Value::Kind::Array;
            ++pos_;
            skip_space();
            if (at(']')) {
                ++pos_;
            } else {
                while (true) {
                    v.items.push_back(value(depth + 1));
                    skip_space();
                    if (at(',')) {
                        ++pos_;
                        continue;
                    }
                    expect(']');
                    break;
                }
            }
        } else if (c == '"') {
            v.kind = Value::Kind::String;
            v.string = string();
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            v.kind = Value::Kind::Number;
            v.number = number();
        } else if (literal("true")) {
            v.kind = Value::Kind::Bool;
            v.boolean = true;
        } else if (literal("false")) {
            v.kind = Value::Kind::Bool;
        } else if (literal("null")) {
            v.kind = Value::Kind::Null;
        } else {
            fail("expected a JSON value");
        }
        return v;
    }

    // JSON number grammar checked here; from_chars (locale-independent) converts it.
    double number() {
        const std::size_t start = pos_;
        auto digits = [&] {
            const std::size_t d = pos_;
            while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9') ++pos_;
            return pos_ - d;
        };
        if (at('-')) ++pos_;
        if (at('0')) {
            ++pos_;
        } else if (digits() == 0) {
            fail("malformed number");
        }
        if (at('.')) {
            ++pos_;
            if (digits() == 0) fail("malformed number");
        }
        if (at('e') || at('E')) {
            ++pos_;
            if (at('+') || at('-')) ++pos_;
            if (digits() == 0) fail("malformed number");
        }
        double v = 0;
        const auto [end, ec] = std::from_chars(text_.data() + start, text_.data() + pos_, v);
        if (ec != std::errc() || end != text_.data() + pos_ || !std::isfinite(v)) {
            pos_ = start;
            fail("number out of the range of a double");
        }
        return v;
    }

    static void append_utf8(std::string& out, std::uint32_t cp) {
        if (cp < 0x80) {
            out += static_cast<char>(cp);
        } else if (cp < 0x800) {
            out += static_cast<char>(0xC0 | (cp >> 6));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else if (cp < 0x10000) {
            out += static_cast<char>(0xE0 | (cp >> 12));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else {
            out += static_cast<char>(0xF0 | (cp >> 18));
            out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        }
    }

    std::uint32_t hex4() {
        if (pos_ + 4 > text_.size()) fail("truncated \\u escape");
        std::uint32_t v = 0;
        const auto [end, ec] = std::from_chars(text_.data() + pos_, text_.data() + pos_ + 4, v, 16);
        if (ec != std::errc() || end != text_.data() + pos_ + 4) fail("malformed \\u escape");
        pos_ += 4;
        return v;
    }

    std::string string() {
        ++pos_;  // opening quote
        std::string out;
        while (true) {
            if (pos_ >= text_.size()) fail("unterminated string");
            const char c = text_[pos_++];
            if (c == '"') return out;
            if (static_cast<unsigned char>(c) < 0x20) {
                --pos_;
                fail("control character in a string");
            }
            if (c != '\\') {
                out += c;
                continue;
            }
            if (pos_ >= text_.size()) fail("unterminated string");
            switch (text_[pos_++]) {
                case '"': out += '"'; break;
                case '\\': out += '\\'; break;
                case '/': out += '/'; break;
                case 'b': out += '\b'; break;
                case 'f': out += '\f'; break;
                case 'n': out += '\n'; break;
                case 'r': out += '\r'; break;
                case 't': out += '\t'; break;
                case 'u': {
                    std::uint32_t cp = hex4();
                    if (cp >= 0xD800 && cp < 0xDC00) {  // a surrogate pair encodes one code point
                        if (!literal("\\u")) fail("unpaired surrogate in \\u escape");
                        const std::uint32_t low = hex4();
                        if (low < 0xDC00 || low >= 0xE000) fail("unpaired surrogate in \\u escape");
                        cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
                    } else if (cp >= 0xDC00 && cp < 0xE000) {
                        fail("unpaired surrogate in \\u escape");
                    }
                    append_utf8(out, cp);
                    break;
                }
                default: --pos_; fail("unknown escape in a string");
            }
        }
    }

    const std::string& path_;
    const std::string& text_;
    std::size_t pos_ = 0;
};

std::string read_text(const std::string& path, std::size_t max_bytes, const char* kind) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(path, "cannot open: " + ec.message());
    if (size > max_bytes)
        throw FormatError(path, "file of " + std::to_string(size) + " bytes is larger than " + std::string(kind) + " can be (" +
                                    std::to_string(max_bytes) + ")");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, "cannot open");
    std::ostringstream s;
    s << in.rdbuf();
    if (in.bad()) throw IoError(path, "read failed");
    return s.str();
}

}  // namespace

Value parse_file(const std::string& path, std::size_t max_bytes, const char* kind) {
    const std::string text = read_text(path, max_bytes, kind);
    return Parser(path, text).document();
}

}  // namespace brdfz::json
