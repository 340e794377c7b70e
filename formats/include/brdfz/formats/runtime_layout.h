// The runtime layout (`.brdfzrt`, formats/SPEC.md §6) of a material: its arrays and its sampler's,
// flat and little-endian, what brdfz::runtime maps and a GPU uploads. The `.brdfz` container stays the
// archive (provenance, metrics); this is what a renderer ships.
#pragma once

#include <string>
#include <vector>

#include "brdfz/brdf.h"

namespace brdfz::runtime_layout {

// The layout's bytes. Tables (every dtype and φd axis, bivariate ones included), factorisations, PCA
// materials (their reconstructed table, float32), φh stacks and analytic models keep what they store;
// a gridded material carries its compact sampler (one is built from it where it has a fine one or
// none). Anything else (an RGL file, a measured table of another kind) is tabulated on 90x90x180 first.
// `describe` is stored for people (empty: brdf.describe()).
std::vector<unsigned char> encode(const Brdf& brdf, const std::string& describe = "");

// encode() written to `path` atomically (a failed or killed write leaves nothing); IoError naming it.
void write(const std::string& path, const Brdf& brdf, const std::string& describe = "");

}  // namespace brdfz::runtime_layout
