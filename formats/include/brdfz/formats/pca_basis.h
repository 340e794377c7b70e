// PCA basis files (formats/SPEC.md, "pca"): a basis is stored once, in a .brdfz container holding the
// basis's mean material (a PCA material with k = 0 and the basis embedded); materials refer to it by
// file name and content hash. Any container with an embedded basis can serve as a basis file.
#pragma once

#include <memory>
#include <string>

#include "brdfz/repr/pca.h"

namespace brdfz::container {

// Writes atomically; IoError when writing fails. Returns the basis with its origin set (this file and
// its content hash), ready for materials that reference it.
std::shared_ptr<const PcaBasis> write_pca_basis(const std::string& path, PcaBasis basis);

// The embedded basis of a .brdfz file, with its origin (path and content hash) set. FormatError when
// the file holds no PCA material or only refers to its basis; the container's own errors otherwise.
std::shared_ptr<const PcaBasis> read_pca_basis(const std::string& path);

// The content hash naming a basis: SHA-256 (FIPS 180-4) over a canonical record of its parameters
// followed by its stored arrays (formats/SPEC.md, "pca"), as 64 lowercase hex digits. It does not
// depend on the container around the basis (creation time, file name), only on what the basis is.
std::string pca_basis_sha256(const PcaBasis& basis);

}  // namespace brdfz::container
