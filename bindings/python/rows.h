// The per-row loops of Brdf's numpy calls (brdf.cpp), in a unit of their own compiled at the library's
// optimisation (CMakeLists.txt: the module's glue is built at -O1), where they vectorise.
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include "brdfz/brdf.h"

namespace brdfz::python {

// out[k] = row begin + k of an (N, 3) array, normalised as the brdfz command normalises directions
// (any finite non-zero vector, in double). Returns the index of the first row that is not such a
// vector, counted from begin, or out.size() when every row is.
std::size_t normalise_rows(const float* xyz, std::size_t begin, std::span<Vec3> out);
std::size_t normalise_rows(const double* xyz, std::size_t begin, std::span<Vec3> out);

// out[k] = row begin + k of an (N, 2) array.
void copy_rows(const float* u, std::size_t begin, std::span<std::array<double, 2>> out);
void copy_rows(const double* u, std::size_t begin, std::span<std::array<double, 2>> out);

// Samples into rows of the wi (N, 3), pdf (N,) and weight (N, 3) arrays, from row `begin`.
void split_samples(std::span<const BrdfSample> s, std::size_t begin, double* wi, double* pdf, double* weight);

}  // namespace brdfz::python
