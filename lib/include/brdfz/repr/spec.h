// ReprSpec: the text that names a representation and its settings, as the CLI, Python and the
// container metadata spell it: "KIND[:KEY=VALUE,KEY=VALUE...]", e.g. "svd:rank=4,space=log",
// "tabular:res=45x45x90,dtype=f16", "analytic:lambert+ggx".
//
// A kind's builder reads its keys with the typed getters below and then calls finish(), which rejects
// any key nobody asked for, so a misspelt option is an error, not a default. compress() first declares
// the keys the kind registered (compress.h): a builder reading a key it did not declare is a bug
// (std::logic_error), so the registry, `brdfz representations` and docs/repr-specs.md cannot drift
// from what the builders read.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace brdfz {

// One key a representation kind takes: its name, its default as text (what the builder uses when the
// key is absent; may say how it depends on other keys) and a one-line help.
struct SpecKey {
    std::string name;
    std::string default_value;
    std::string help;
};

class ReprSpec {
public:
    // Throws ValueError naming the spec when it is malformed (empty kind, "key" without "=", a key
    // given twice). A part after ':' without '=' is the kind's positional argument (the analytic
    // model string), available as positional().
    static ReprSpec parse(const std::string& text);

    const std::string& kind() const { return kind_; }
    const std::string& positional() const { return positional_; }
    std::string str() const;  // canonical text, options in the order given

    // Typed getters: the value of KEY, or the fallback when absent. ValueError on a value that does
    // not parse ("rank=four") or is out of the given range.
    int get_int(const std::string& key, int fallback, int min_value, int max_value) const;
    double get_double(const std::string& key, double fallback) const;
    std::string get_string(const std::string& key, const std::string& fallback) const;
    // One of `choices`; ValueError listing them otherwise.
    std::string get_choice(const std::string& key, const std::string& fallback,
                           const std::vector<std::string>& choices) const;
    // "AxBxC" with `n` positive parts, e.g. res=45x45x90 (n = 3) or res=90x90 (n = 2).
    std::vector<int> get_dims(const std::string& key, const std::vector<int>& fallback) const;
    bool has(const std::string& key) const;

    // The keys the kind takes and whether it takes a positional argument: a positional part given to a
    // kind that takes none, or a declared key given without a value, is a ValueError naming it (as a
    // misspelt key is); a getter asking for an undeclared key is std::logic_error.
    void declare(const std::vector<SpecKey>& keys, bool takes_positional);

    // ValueError naming every option no getter asked for (a misspelt key).
    void finish() const;

private:
    const std::string* find(const std::string& key) const;

    std::string kind_;
    std::string positional_;
    std::vector<std::pair<std::string, std::string>> options_;
    mutable std::vector<bool> used_;
    const std::vector<SpecKey>* declared_ = nullptr;
};

}  // namespace brdfz
