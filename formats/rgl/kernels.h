// RglBrdf's batch kernels (formats/rgl/kernels.cpp): eval, pdf and sample with its weight over arrays
// of pairs, built for each of Highway's targets and run at the level asked for (brdfz/simd.h).
// One call at a time runs them on one pair, so a pair's result does not depend on its batch.
//
// Tables blended between two θi slices store the slices innermost: entry i of slice s at i·stride + s,
// stride = the number of slices, at least 2 (a single slice is stored twice), so that both slices of an
// entry are one 8-byte read; one float of padding follows the last entry.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/simd.h"

namespace brdfz::rgl::detail {

// The slice stride for `slices` slices, and a stack of `slices` tables of `entries` values each (slice
// by slice, as the files store them) in the kernels' layout.
inline std::size_t slice_stride(std::size_t slices) { return slices < 2 ? 2 : slices; }
inline std::vector<float> slices_innermost(const float* values, std::size_t slices, std::size_t entries) {
    const std::size_t stride = slice_stride(slices);
    std::vector<float> out(entries * stride + 1, 0.0f);
    for (std::size_t s = 0; s < stride; ++s)
        for (std::size_t i = 0; i < entries; ++i) out[i * stride + s] = values[(s < slices ? s : 0) * entries + i];
    return out;
}

// A warp's tables (Marginal2D), slices innermost: rows × cols densities normalised to integrate to 1,
// rows × (cols − 1) conditional CDF entries (along x, at each patch's right edge) and rows − 1 marginal
// ones (along y, at each patch row's top edge).
struct WarpTables {
    int rows = 0, cols = 0, stride = 2;
    const float* data = nullptr;
    const float* cond = nullptr;
    const float* marg = nullptr;
};

// rows × cols float32 samples spanning [0, 1]², x along columns (stored fastest).
struct GridTable {
    int rows = 0, cols = 0;
    const float* values = nullptr;
};

// What the kernels read; every index into these fits an int (RglBrdf checks the sizes).
struct KernelTables {
    const float* theta_i = nullptr;  // the θi the slices are tabulated at, increasing
    int n_theta = 0;
    GridTable ndf, sigma;  // one slice each
    // rgb_rows × rgb_cols points, channel c of point i in slice s at ((3i + c)·stride + s), the warps'
    // stride: slices innermost, as theirs.
    int rgb_rows = 0, rgb_cols = 0;
    const float* rgb = nullptr;
    WarpTables vndf;
    WarpTables luminance;  // data null: sampling uses the VNDF warp alone
    bool jacobian = true;
};

// out[k] = f(wi[k], wo[k]) (rgl.h), 0 below the horizon and wherever it would not be finite.
void eval_pairs(Simd simd, const KernelTables& t, const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n);
// out[k] = Brdf::pdf(wo[k], wi[k]).
void pdf_pairs(Simd simd, const KernelTables& t, const Vec3* wo, const Vec3* wi, double* out, std::size_t n);
// out[k] = Brdf::sample(wo[k], u[k][0], u[k][1]), its weight included.
void sample_pairs(Simd simd, const KernelTables& t, const Vec3* wo, const std::array<double, 2>* u,
                  BrdfSample* out, std::size_t n);

// The warp's sample() from the tables of one slice at each (x[k], y[k]) in [0, 1]², in place, and the
// density at the point drawn in pdf[k] (the writer derives tables with it: formats/rgl/writer.cpp).
void sample_warp(const WarpTables& w, int slice, double* x, double* y, double* pdf, std::size_t n);

}  // namespace brdfz::rgl::detail
