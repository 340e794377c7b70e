// Compiled into every program that links brdfz::formats (its INTERFACE_SOURCES, formats/CMakeLists.txt):
// a reference to the library's kind registration (kinds.cpp), which nothing else refers to. It makes
// the linker keep it, the object of a static archive as the shared library under --as-needed, so that
// the `rgl_svd` kind is registered wherever brdfz::formats is linked.
extern "C" const int brdfz_formats_kinds;

namespace {
[[gnu::used]] const int* const keep_brdfz_formats_kinds = &brdfz_formats_kinds;
}  // namespace
