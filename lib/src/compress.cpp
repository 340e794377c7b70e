#include "brdfz/compress.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "brdfz/errors.h"

namespace brdfz {
namespace kinds {
// Generated from lib/src/repr/kinds/*.cpp (cmake/registry.cmake).
void register_all(std::vector<ReprKind>& out);
}  // namespace kinds

namespace {

template <typename Build>
Compressed timed(const ReprSpec& spec, Build build) {
    const auto start = std::chrono::steady_clock::now();
    Compressed out = build();
    out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.spec = spec.str();
    return out;
}

// What add_representation_kinds was given, and whether the list was built.
struct Additions {
    std::vector<void (*)(std::vector<ReprKind>&)> registrations;
    bool listed = false;
};

Additions& additions() {
    static Additions a;
    return a;
}

// The kind a spec names, its keys declared on the spec; SpecError naming the known kinds otherwise.
const ReprKind& kind_of(ReprSpec& spec) {
    const ReprKind* kind = find_representation_kind(spec.kind());
    if (!kind) {
        std::string known;
        for (const std::string& name : compress_kinds()) known += (known.empty() ? "" : ", ") + name;
        throw SpecError("unknown representation '" + spec.kind() + "' (known: " + known + ")");
    }
    // A key the kind does not declare is refused by ReprSpec::finish; phih gets its own message.
    if (spec.has("phih") && std::none_of(kind->keys.begin(), kind->keys.end(), [](const SpecKey& k) { return k.name == "phih"; }))
        throw ValueError("phih is not supported by " + spec.kind() + ": it has no φh axis (tabular, svd and nmf do)");
    spec.declare(kind->keys, !kind->positional.empty());
    return *kind;
}

}  // namespace

const std::vector<ReprKind>& representation_kinds() {
    static const std::vector<ReprKind> kinds = [] {
        std::vector<ReprKind> out;
        kinds::register_all(out);
        for (auto registration : additions().registrations) registration(out);
        additions().listed = true;
        std::sort(out.begin(), out.end(), [](const ReprKind& a, const ReprKind& b) { return a.name < b.name; });
        return out;
    }();
    return kinds;
}

void add_representation_kinds(void (*register_kinds)(std::vector<ReprKind>& out)) {
    if (additions().listed) throw std::logic_error("add_representation_kinds: the kinds were listed already");
    additions().registrations.push_back(register_kinds);
}

const ReprKind* find_representation_kind(const std::string& name) {
    for (const ReprKind& kind : representation_kinds())
        if (kind.name == name) return &kind;
    return nullptr;
}

std::vector<std::string> compress_kinds() {
    std::vector<std::string> out;
    for (const ReprKind& kind : representation_kinds()) out.push_back(kind.name);
    return out;
}

void check_spec(const std::string& text) {
    ReprSpec spec = ReprSpec::parse(text);
    kind_of(spec);
}

Compressed compress(const Brdf& source, const std::string& text, const CompressOptions& options) {
    ReprSpec spec = ReprSpec::parse(text);
    const ReprKind& kind = kind_of(spec);
    return timed(spec, [&] { return kind.build(source, spec, options); });
}

Compressed compress(const MeasurementSet& source, const std::string& text, const CompressOptions& options) {
    ReprSpec spec = ReprSpec::parse(text);
    const ReprKind& kind = kind_of(spec);
    if (!kind.build_measurements)
        throw ValueError("'" + spec.kind() + "' needs a BRDF on a grid; scattered measurements can only be fitted "
                         "(analytic:MODEL)");
    return timed(spec, [&] { return kind.build_measurements(source, spec, options); });
}

}  // namespace brdfz
