// Compiled into every program that links brdfz::fit (its INTERFACE_SOURCES, lib/fit/CMakeLists.txt):
// a reference to the library's kind registration (src/kinds.cpp), which nothing else refers to. It
// makes the linker keep it, the object of a static archive as the shared library under --as-needed,
// so that the `analytic` kind is registered wherever brdfz::fit is linked.
extern "C" const int brdfz_fit_kinds;

namespace {
[[gnu::used]] const int* const keep_brdfz_fit_kinds = &brdfz_fit_kinds;
}  // namespace
