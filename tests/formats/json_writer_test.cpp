#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <sstream>

#include "brdfz/formats/json_writer.h"

using brdfz::json::Writer;

namespace {

std::string write(int indent) {
    std::ostringstream os;
    Writer j(os, indent);
    j.begin_object();
    j.key("name").value("a \"quoted\"\\path\n");
    j.key("n").value(std::size_t{3}).key("x").value(0.1).key("nan").value(std::nan("")).key("inf").value(
        std::numeric_limits<double>::infinity());
    j.key("ok").value(true);
    j.key("list").begin_array().value(1.0).value(-2.5).begin_object().end_object().end_array();
    j.key("empty").begin_array().end_array();
    j.end_object();
    return os.str();
}

}  // namespace

TEST_CASE("json writer: one line, or indented, with escapes, 17 digits and null for non-finite numbers", "[json]") {
    CHECK(write(0) ==
          R"({"name": "a \"quoted\"\\path\u000a", "n": 3, "x": 0.10000000000000001, "nan": null, "inf": null, )"
          R"("ok": true, "list": [1, -2.5, {}], "empty": []})");
    CHECK(write(2) == "{\n"
                      "  \"name\": \"a \\\"quoted\\\"\\\\path\\u000a\",\n"
                      "  \"n\": 3,\n"
                      "  \"x\": 0.10000000000000001,\n"
                      "  \"nan\": null,\n"
                      "  \"inf\": null,\n"
                      "  \"ok\": true,\n"
                      "  \"list\": [\n"
                      "    1,\n"
                      "    -2.5,\n"
                      "    {}\n"
                      "  ],\n"
                      "  \"empty\": []\n"
                      "}");
}
