// The sampler of a gridded representation (sample/grid_sampler.h) in its /representation group
// (formats/SPEC.md §3, "sampler"), shared by the storage modules of tables, factorisations, PCA and φh
// stacks: a group "sampler" whose attribute "kind" says compact, fine or none, and for a compact
// sampler its tables, so that a material loads ready to sample without evaluating anything. A fine
// sampler is rebuilt from eval at load (1.6 MB of derived tables); a file without the group (written
// before version 6) gets a compact sampler built at load. The group is derived data, not a feature: a
// reader that does not know it ignores it and builds its own sampler, so files stay readable by the
// versions their features name.
#pragma once

#include <optional>

#include "brdfz/formats/container.h"
#include "brdfz/sample/grid_sampler.h"
#include "h5.h"

namespace brdfz::container::detail {

// `compact` holds the tables when kind is Compact.
void write_sampler(h5::WriteNode& rep, SamplerKind kind, const CompactSampler* compact);
inline void write_sampler(h5::WriteNode& rep, const GridSampler& sampler) {
    write_sampler(rep, sampler.kind(), sampler.compact());
}

// What a group says: the kind to build, or the stored compact sampler. FormatError naming the file and
// the object for an unknown kind or tables that do not make a sampler.
struct StoredSampler {
    SamplerKind kind = SamplerKind::Compact;
    std::optional<CompactSampler> compact;
};
StoredSampler read_sampler(const h5::ReadNode& rep);

// A representation read from `rep` with the sampler it stores: make(kind) or make(compact).
template <typename Make>
auto with_sampler(const h5::ReadNode& rep, Make&& make) {
    StoredSampler s = read_sampler(rep);
    return s.compact ? make(std::move(*s.compact)) : make(s.kind);
}

}  // namespace brdfz::container::detail
