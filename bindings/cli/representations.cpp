// brdfz representations [--json | --markdown]: the registered representation kinds and their keys
// (compress.h, ReprKind). --markdown prints the table docs/repr-specs.md holds, which a test compares.
#include <iostream>

#include "brdfz/compress.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

// Markdown cells hold no raw '|'.
std::string cell(const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
}

void print_markdown(std::ostream& os) {
    os << "| kind | key | default | what it sets |\n|---|---|---|---|\n";
    for (const ReprKind& k : representation_kinds()) {
        os << "| `" << k.name << "` | " << (k.positional.empty() ? "" : "`" + k.positional + "` (positional)") << " | | "
           << cell(k.summary) << " |\n";
        for (const SpecKey& key : k.keys)
            os << "| | `" << key.name << "` | " << cell(key.default_value) << " | " << cell(key.help) << " |\n";
    }
}

}  // namespace

void add_representations(CLI::App& app) {
    auto json = std::make_shared<bool>(false);
    auto markdown = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("representations", "the representation kinds compress builds, with their keys");
    cmd->add_flag("--json", *json, "print JSON");
    cmd->add_flag("--markdown", *markdown, "print the table of docs/repr-specs.md");
    cmd->callback([json, markdown] {
        if (*markdown) return print_markdown(std::cout);
        if (*json) {
            JsonWriter j(std::cout);
            j.begin_array();
            for (const ReprKind& k : representation_kinds()) {
                j.begin_object();
                j.key("kind").value(k.name);
                j.key("summary").value(k.summary);
                j.key("positional").value(k.positional);
                j.key("measurements").value(k.build_measurements != nullptr);
                j.key("keys").begin_array();
                for (const SpecKey& key : k.keys) {
                    j.begin_object();
                    j.key("name").value(key.name).key("default").value(key.default_value).key("help").value(key.help);
                    j.end_object();
                }
                j.end_array();
                j.end_object();
            }
            j.end_array();
            std::cout << "\n";
            return;
        }
        for (const ReprKind& k : representation_kinds()) {
            std::cout << k.name << (k.positional.empty() ? "" : ":" + k.positional) << "  " << k.summary << "\n";
            for (const SpecKey& key : k.keys)
                std::cout << "    " << key.name << "=" << key.default_value << "  " << key.help << "\n";
        }
    });
}

}  // namespace brdfz::cli
