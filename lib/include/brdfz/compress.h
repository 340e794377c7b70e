// compress(): build any compact representation of a Brdf from its ReprSpec text — the one entry
// point behind `brdfz compress`, Python's brdfz.compress and the budget-driven selection.
//
// Kinds register themselves (ReprKind below): `brdfz representations` lists them with their keys,
// docs/repr-specs.md documents them, and each kind's builder lives in lib/src/repr/kinds/, or in the
// kinds/ folder of the library that adds it (lib/fit/src/kinds/: `analytic`, with brdfz::fit).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/measurements.h"
#include "brdfz/repr/spec.h"

namespace brdfz {

class PcaBasis;

struct CompressOptions {
    int threads = 0;  // 0: one per hardware thread
    // Fraction done (0..1]; may be called from worker threads, under a lock.
    std::function<void(double)> progress;
    // Reads the PCA basis a spec names (pca:basis=FILE). The core reads no files: brdfz::formats
    // supplies the reader (formats/io.h, with_file_access()); unset, a pca spec is a ValueError.
    std::function<std::shared_ptr<const PcaBasis>(const std::string& path)> load_pca_basis;
};

struct Compressed {
    std::unique_ptr<Brdf> brdf;
    std::string spec;               // canonical spec text (ReprSpec::str())
    double build_seconds = 0;       // wall time of compress()
    std::vector<std::string> notes; // what the builder wants the user to know (fit status, clamping)
};

// SpecError (a ValueError) for an unknown kind or a bad option (naming it); the builders' own errors
// pass through.
Compressed compress(const Brdf& source, const std::string& spec, const CompressOptions& options = {});

// SpecError, without building anything, for a spec that does not parse, names an unknown kind, or
// gives a bare word or a key the kind does not take (its values are checked when it is built).
void check_spec(const std::string& spec);

// Scattered measurements (Cornell, ALTA) have no grid to factor or resample: only `analytic` fits
// them; ValueError for any other kind.
Compressed compress(const MeasurementSet& source, const std::string& spec, const CompressOptions& options = {});

// A representation kind, registered from its own file lib/src/repr/kinds/NAME.cpp, which defines
// `void brdfz::kinds::register_NAME(std::vector<ReprKind>&)`; the build finds the file and calls it
// (cmake/registry.cmake), so no central file lists kinds. A library on top of the core registers its
// kinds' files the same way, into a function it hands to add_representation_kinds.
struct ReprKind {
    std::string name;                 // the spec's KIND
    std::string summary;              // one line: what it is
    std::string positional;           // what a positional argument names (analytic: "MODEL"); empty: none
    std::vector<SpecKey> keys;        // every key the builder reads, with defaults and help
    Compressed (*build)(const Brdf& source, const ReprSpec& spec, const CompressOptions& options) = nullptr;
    // Scattered measurements; nullptr when the kind needs a BRDF it can evaluate anywhere.
    Compressed (*build_measurements)(const MeasurementSet& source, const ReprSpec& spec,
                                     const CompressOptions& options) = nullptr;
    // Whether the kind can be built from this source (rgl_svd: an RGL-EPFL material's own tensors);
    // nullptr: from any. default_candidates(source) leaves out the kinds that cannot.
    bool (*applies)(const Brdf& source) = nullptr;
};

// Every registered kind, in name order.
const std::vector<ReprKind>& representation_kinds();
// nullptr for an unknown name.
const ReprKind* find_representation_kind(const std::string& name);

// The kinds' names, for help texts.
std::vector<std::string> compress_kinds();

// Adds the kinds of a library on top of the core (brdfz::fit): `register_kinds` is called beside the
// core's own registration when the kinds are first listed. Call it from a static initialiser, before
// that; std::logic_error after.
void add_representation_kinds(void (*register_kinds)(std::vector<ReprKind>& out));

}  // namespace brdfz
