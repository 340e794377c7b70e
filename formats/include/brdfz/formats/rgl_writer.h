// Writing RGL-EPFL `.bsdf` files (RGB, isotropic or anisotropic), so any brdfz representation can be rendered by
// Mitsuba 3's `measured` plugin. The reader and the parameterisation are described in rgl.h.
//
// An RglBrdf is written with its own tensors. Any other Brdf is tabulated into the
// parameterisation's tables (Dupuy & Jakob 2018), taken as isotropic (wi in the xz-plane), with
// tables chosen for that BRDF rather than for a measurement:
//   ndf    D(θm) ∝ Y(f(w, w))·cos²θ (a microfacet BRDF's retro-reflection is F·D·G/(4cos²θ)),
//          normalised to ∫D cosθ dω = 1 and mixed with 20% of the uniform D = 1/π;
//   sigma  the projected area σ(wi) = ∫ D(m) max(0, m·wi) dωm;
//   vndf   per θi slice, the warp of the unit square onto microfacet normals m (u_θm, u_φm relative
//          to φi) that decides where the rgb samples go: 70% the BRDF's reflected energy at this θi,
//          Y(f(wi, wo))·cosθo·dωo/du_m with wo = wi reflected about m, and 30% cosθo·dωo/du_m, so
//          that every reflected direction keeps samples;
//   rgb    per θi slice, at each grid point s: the value from which readers reproduce f(wi, wo) for
//          m = warp(s), f·cosθo·4σ(wi)/D(m) with D and σ as interpolated from the stored tables
//          (jacobian flag 1; 0 below the horizon). Dividing by D flattens a microfacet lobe, so the
//          bilinear interpolation between grid points is accurate inside the highlight;
//   luminance  Y(f)·cosθo per unit of the square, Y·(dωo/du_m)/pdf(u_m) (plus 1e-3 of its slice
//          mean): sampling by it and the warp draws wo in proportion to Y(f)·cosθo.
// θi slices are spaced evenly from 0 to 89°; Mitsuba uses the last one beyond it.
// With n_phi_i >= 3 the file is anisotropic (formats/rgl/aniso.h): φi slices spaced evenly over
// [-π, π] (both ends, so no folding), every table built as above with wi at (θi, φi) and absolute
// microfacet azimuths; ndf and sigma are ndf_resolution² tables over (u_θ, u_φ), sigma by quadrature. Readers reproduce
// f exactly at the grid points and interpolate between them and between slices, which is the
// approximation: its size is measured by tests/python/test_rgl_write_mitsuba.py.
#pragma once

#include <string>

#include "brdfz/brdf.h"
#include "brdfz/formats/rgl.h"

namespace brdfz::rgl {

struct WriteOptions {
    int n_theta_i = 24;        // θi slices
    int n_phi_i = 1;           // φi slices: 1, an isotropic file; 3..4096, an anisotropic one (below)
    int vndf_resolution = 128;  // vndf grid, square
    int rgb_resolution = 64;   // rgb and luminance grids, square
    int ndf_resolution = 128;  // ndf and sigma: columns along u_θ (2 rows in φ: isotropic)
    std::string description;   // empty: the BRDF's describe()
};

// The tensors for any Brdf, as described above. ValueError for resolutions outside 2..4096.
Tensors derive(const Brdf& brdf, const WriteOptions& options = {});

// Writes an RglBrdf's own tensors (adding luminance when it has none), or derive()d ones, as a
// tensor_file. Atomic; IoError when writing fails. Returns the number of rgb grid points written
// (θi slices × rows × columns).
std::size_t write(const std::string& path, const Brdf& brdf, const WriteOptions& options = {});

}  // namespace brdfz::rgl
