// What several kinds' builders share: reading the keys they have in common, and the notes a
// tabulation leaves for Compressed::notes.
#pragma once

#include <functional>
#include <string>

#include "brdfz/compress.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/repr/phi_h.h"
#include "brdfz/table.h"
#include "brdfz/tabulate.h"

namespace brdfz::kinds {

inline const SpecKey kLookupKey{"lookup", "linear", "linear|nearest: interpolation of the stored grid"};
inline const SpecKey kWarpKey{"dwarp", "0", "in [0, 0.95]: θd bins narrowing towards grazing (0: linear axis)"};
inline const SpecKey kThetaHWarpKey{
    "hwarp", "0",
    "0|auto|D: the θh axis, square-root (0), or warped by a specular peak of scale D degrees (0.01-45), about half "
    "its bins within D of the pole; auto: D three half widths of the source's own peak, the square-root axis when "
    "it has none"};
inline const SpecKey kSymmetryKey{"symmetry", "reciprocal",
                                  "reciprocal|none: φd over [0, π), a pair and its exchange sharing a bin (their mean), "
                                  "or over [0, 2π), non-reciprocal data kept"};
inline const SpecKey kWeightKey{"weight", "bins",
                                "bins|solid: the lsq fit's points weighed as the grid's bins, or by solid angle (the "
                                "metrics over directions)"};

// The φh axis (repr/phi_h.h) of the kinds that take one: phih=N and a symmetry= that may be bilateral.
inline const SpecKey kPhiHKey{"phih", "1",
                              "φh slices, at most " + std::to_string(PhiHBrdf::kMaxTableSlices) + " (tabular) or " +
                                  std::to_string(PhiHBrdf::kMaxFactoredSlices) +
                                  " (svd, nmf), what a .brdfz file holds: 1 isotropic (no φh axis); N >= 2 one table "
                                  "per half-vector azimuth, interpolated linearly (anisotropic data)"};
inline const SpecKey kPhiHSymmetryKey{
    "symmetry", "reciprocal",
    "reciprocal|none|bilateral: φd over [0, π) (a pair and its exchange sharing a bin) or [0, 2π); bilateral, the "
    "mirror y -> -y: with phih = 1 φd over [0, π] (a pair and its mirror image sharing a bin: non-reciprocal data kept "
    "in none's accuracy at half its φd bins), with phih >= 2 φh over [0, π] and φd over [0, 2π)"};

inline const SpecKey kSamplerKey{"sampler", "compact",
                                 "compact|fine: the importance sampler, ~14 KB of CDFs stored with the representation, "
                                 "or the 1.6 MB half-vector sampler built from eval at load"};
// sampler=compact|fine.
SamplerKind sampler_option(const ReprSpec& spec);

// symmetry= of a kind with a φh axis, `fallback` when absent: the mirror fold of the φh axis with
// phih >= 2 (PhiHSymmetry::Bilateral), else of φd (Symmetry::Bilateral).
std::string phi_h_symmetry_option(const ReprSpec& spec, Symmetry fallback = Symmetry::Reciprocal);

// phih=N slices of `source` (tabulate_phi_h), each built by build_slice from the rotated source with
// the slices' φd symmetry and sampler (none when the stack has its own compact sampler, fine for a
// fine one); their notes once each.
Compressed build_phi_h(const Brdf& source, int n, PhiHSymmetry symmetry, SamplerKind sampler,
                       const std::function<Compressed(const Brdf&, Symmetry, SamplerKind)>& build_slice);

// What tabulating `source` left out or changed.
void note_tabulation(const Brdf& source, const Tabulated& t, Compressed& out);

Lookup lookup_option(const ReprSpec& spec);
// dwarp=W (GridSpec::theta_d_warp).
double theta_d_warp_option(const ReprSpec& spec);
// hwarp=auto's scale in peak half widths: wide enough that the bins beyond the peak still follow the
// lobe around it, narrow enough that the peak itself spans several bins.
inline constexpr double kPeakHalfWidths = 3.0;
// The source's specular peak: the median over θd of the θh at which the luminance, averaged over φd,
// falls to half its maximum above its value at 30°; 0 when it has no peak there (a maximum not twice
// that value: a matte material).
double specular_peak_half_width(const Brdf& source);
// hwarp=0|auto|D (GridSpec::theta_h_warp, radians), auto's choice for `source` said in `notes`.
double theta_h_warp_option(const ReprSpec& spec, const Brdf& source, std::vector<std::string>& notes);
// symmetry=reciprocal|none (GridSpec::symmetry), `fallback` when absent, for the kinds without the
// bilateral fold: ValueError for symmetry=bilateral, saying `why_not` the kind has it.
Symmetry symmetry_option(const ReprSpec& spec, const std::string& why_not, Symmetry fallback = Symmetry::Reciprocal);
// weight=bins|solid (TabulateOptions::FitWeight), a key of the least-squares fits only (`lsq`).
TabulateOptions::FitWeight weight_option(const ReprSpec& spec, bool lsq);

// tabulate(source, tab) (its grid validated first), with the notes it leaves in `out`.
Tabulated tabulate_noted(const Brdf& source, const TabulateOptions& tab, Compressed& out);

}  // namespace brdfz::kinds
