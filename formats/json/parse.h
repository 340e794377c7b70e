// A small strict JSON parser (RFC 8259: no comments, no trailing commas, no NaN, no duplicate keys),
// shared by the JSON file formats (analytic models, scenes). Errors name the file, line and column.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace brdfz::json {

struct Value {
    enum class Kind { Null, Bool, Number, String, Array, Object } kind = Kind::Null;
    bool boolean = false;
    double number = 0;
    std::string string;
    std::vector<Value> items;       // array elements, or object values
    std::vector<std::string> keys;  // object keys, parallel to items

    const Value* member(const std::string& key) const {
        for (std::size_t i = 0; i < keys.size(); ++i)
            if (keys[i] == key) return &items[i];
        return nullptr;
    }
};

const char* kind_name(Value::Kind k);  // "an object", "a number", ...

// Reads and parses a whole file of at most max_bytes (checked before reading). IoError when it cannot
// be read; FormatError naming the file (and line and column) when it is too large for `kind` ("a model
// file") or not JSON.
Value parse_file(const std::string& path, std::size_t max_bytes, const char* kind);

}  // namespace brdfz::json
