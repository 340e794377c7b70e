// Storage modules: one per representation, each in its own file container/storage/NAME.cpp, which
// defines `void register_NAME(std::vector<const StorageModule*>&)`; the build finds the file and calls
// it (cmake/registry.cmake). A module writes one kind of Brdf into the /representation group and reads
// it back; it names the features (formats/SPEC.md) an object needs, so files record exactly what a
// reader must understand. Adding a representation: its file here and its section in formats/SPEC.md.
#pragma once

#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "brdfz/formats/container.h"
#include "brdfz/formats/io.h"
#include "h5.h"

namespace brdfz::container::detail {

// What the root's units, cosine and conventions attributes say (formats/SPEC.md §2): the meaning of
// every stored value. A reader refuses a file that says anything else.
inline constexpr const char* kUnits = "1/sr";
inline constexpr const char* kCosine = "excluded";
inline constexpr const char* kConventions =
    "normal +z; wi and wo unit vectors pointing away from the surface; values are f_r(wi, wo) in linear RGB";

struct ReadContext {
    Lookup lookup = Lookup::Linear;
};

struct StorageModule {
    std::string_view type;          // value of the /representation group's "type" attribute
    std::vector<Feature> features;  // every feature this module's files may use
    // The features storing this object needs; empty when the module cannot store it exactly.
    std::vector<Feature> (*needs)(const Brdf& brdf);
    void (*write)(h5::WriteNode& rep, const Brdf& brdf);
    // FormatError (naming the file and object) for invalid contents; shapes bounded before allocating.
    std::unique_ptr<Brdf> (*read)(const h5::ReadNode& rep, const ReadContext& ctx);
    // What `brdfz info` says of an object read(): dims and what they count, the range of its values
    // and its valid entries; info.format and the container's counts are set already.
    void (*source_info)(const Brdf& brdf, SourceInfo& info);
};

// Every module, by type name; the writer stores an object with the one whose needs() are not empty.
std::span<const StorageModule* const> storage_modules();
const StorageModule* find_storage(std::string_view type);

// The θd axis of a grid (formats/SPEC.md, `theta_d_axis`/`theta_d_warp`), shared by the modules that
// store grids (tabular.cpp): nothing is written for the linear axis; reading returns its warp (0: linear)
// and throws FormatError for an unknown axis or a warp outside (0, GridSpec::kMaxWarp].
void write_theta_d_axis(h5::WriteNode& rep, const GridSpec& g);
double read_theta_d_warp(const h5::ReadNode& rep);
// The θh axis likewise (`theta_h_axis`, `theta_h_warp`): "sqrt" for the square-root axis, "warped"
// and its scale in radians for GridSpec::theta_h_warp; reading throws FormatError for an unknown axis or
// a scale outside [GridSpec::kMinThetaHWarp, kMaxThetaHWarp].
void write_theta_h_axis(h5::WriteNode& rep, const GridSpec& g);
double read_theta_h_warp(const h5::ReadNode& rep);
// The φd axis likewise (formats/SPEC.md, `phi_d_axis`): nothing for the reciprocal [0, π), "full" for
// Symmetry::None, "bilateral" for Symmetry::Bilateral; reading throws FormatError for another value.
void write_phi_d_axis(h5::WriteNode& rep, const GridSpec& g);
Symmetry read_phi_d_symmetry(const h5::ReadNode& rep);

// A stored grid's attributes (formats/SPEC.md: `grid`, `bin_position`, and the θh and θd axes where the
// module stores warped ones, else the square-root and linear ones; the φd axis), checked: FormatError
// names the attribute that is out of range before anything is allocated.
GridSpec read_grid(const h5::ReadNode& rep, bool warped_axes);

// Features of the container itself (layout, metadata, CRC-32C checksums).
inline const Feature kCore{"core", 1};

}  // namespace brdfz::container::detail
