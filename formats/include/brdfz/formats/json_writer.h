// Streaming JSON output: the one writer behind every JSON the project prints or writes (the CLI's
// --json reports on one line, analytic model files indented; docs/model-json.md). Objects and arrays
// nest and commas are placed automatically. Numbers are written with 17 significant digits, so they
// read back to the same double; non-finite ones as null, since JSON has no NaN or infinity.
#pragma once

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace brdfz::json {

class Writer {
public:
    // indent 0: everything on one line, items separated by ", ". indent > 0: one item per line,
    // nested `indent` spaces deeper than its container.
    explicit Writer(std::ostream& os, int indent = 0) : os_(os), indent_(indent) {}
    Writer& begin_object();
    Writer& end_object();
    Writer& begin_array();
    Writer& end_array();
    Writer& key(const std::string& k);
    Writer& value(double v);
    Writer& value(std::size_t v);
    Writer& value(const std::string& v);
    Writer& value(const char* v);  // not value(bool): a pointer would convert to it
    Writer& value(bool v);

private:
    void separate();
    void close(char bracket);
    std::ostream& os_;
    int indent_;
    std::vector<bool> first_{true};  // per open container (and the top level): nothing written in it yet
    bool after_key_ = false;
};

}  // namespace brdfz::json
