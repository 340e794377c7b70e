// Hands the kinds of kinds/ to the core's registry (compress.h) when the library is loaded. Nothing
// calls into this file: every program that links brdfz::formats refers to brdfz_formats_kinds
// (keep_kinds.cpp), so that the linker keeps it and its initialiser.
#include <vector>

#include "brdfz/compress.h"

namespace brdfz::kinds {
// Generated from kinds/*.cpp (cmake/registry.cmake).
void register_formats(std::vector<ReprKind>& out);
}  // namespace brdfz::kinds

extern "C" const int brdfz_formats_kinds = (brdfz::add_representation_kinds(brdfz::kinds::register_formats), 1);
