// RglBrdf's batch kernels (kernels.h): the Dupuy-Jakob parameterisation as Mitsuba 3's `measured`
// plugin evaluates and samples it (rgl.h), over blocks of pairs in passes across arrays of numbers, as
// the table kernels do (lib/src/detail/table_lookup.h). Written once and compiled for each of Highway's
// targets (lib/runtime/src/hwy_dispatch.h picks one at run time): the arithmetic passes are
// branch-free loops without libm calls, which the compiler vectorises for the target; the table reads
// between them are Highway vectors, each lane's two θi slices of an entry one 8-byte read (kernels.h).
//
// Arithmetic is in double over the float32 tables, operation for operation the scalar warps' (Mitsuba's
// Marginal2D, after Dupuy & Jakob 2018), with two substitutions that vectorise: angles by the
// polynomial arctangent detail::atan01 (6e-11 relative) instead of asin and atan2, and the sampled
// normal's sines and cosines from detail::sincos_half_turn (a few ulp) instead of libm's. Without FMA
// contraction (brdfz_float), so every target gives the same bits, and a pair's result does not depend
// on the batch it is in.
#include "kernels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>

#include "detail/fast_math.h"
#include "detail/simd.h"

// Compiled once per Highway target (hwy/foreach_target.h includes this file again for each).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "rgl/kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace brdfz::rgl::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kBlock = 64;  // pairs per pass, a multiple of every build's lanes

// NaN goes to 0, so every later float-to-integer conversion is defined. Two selects in the operand order
// of x86's max and min (which return the second operand for NaN): one instruction each, where
// std::fmin/fmax are calls and a nested select is a compare-and-blend chain.
[[gnu::always_inline]] inline double clamp01(double v) {
    const double a = v > 0.0 ? v : 0.0;
    return a < 1.0 ? a : 1.0;
}
[[gnu::always_inline]] inline double lerp(double a, double b, double t) { return a * (1.0 - t) + b * t; }
[[gnu::always_inline]] inline bool finite(double v) { return std::fabs(v) < kInf; }
[[gnu::always_inline]] inline bool finite(const Vec3& v) {
    const bool x = finite(v.x), y = finite(v.y), z = finite(v.z);
    return x & y & z;  // not &&: no branches in the lane loops
}

// atan2(y, x) through atan01, with std::atan2's quadrants and signed zeros (x's sign by copysign, which
// vectorises where std::signbit does not).
[[gnu::always_inline]] inline double atan2_poly(double y, double x) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    const double hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    const double a = ::brdfz::detail::atan01(hi > 0.0 ? lo / hi : 0.0);
    const double b = ay > ax ? kPi / 2 - a : a;
    return std::copysign(std::copysign(1.0, x) < 0.0 ? kPi - b : b, y);
}

// The parameterisation's unit coordinates: a square-root axis in elevation, linear in azimuth.
[[gnu::always_inline]] inline double u_of_theta(double theta) { return std::sqrt(theta * (2.0 / kPi)); }
[[gnu::always_inline]] inline double u_of_phi(double phi) { return (phi + kPi) * (0.5 / kPi); }

// Integral over the first fraction t of a segment of length `width` along which a function goes
// linearly from v0 to v1.
[[gnu::always_inline]] inline double partial_integral(double t, double width, double v0, double v1) {
    return t * lerp(v0, v1, 0.5 * t) * width;
}

// Inverse of partial_integral on a unit-width segment, for v0, v1 >= 0: rationalised,
// 2s / (v0 + √(v0² + 2s(v1 − v0))), without cancellation or a special case for v0 ≈ v1 (Mitsuba switches
// to the constant-density solution there, off by up to 1e-4 relative: its pdf would not quite be the
// density it draws from).
[[gnu::always_inline]] inline double invert_partial_integral(double s, double v0, double v1) {
    const double r = v0 * v0 + 2.0 * s * (v1 - v0);
    const double denom = v0 + std::sqrt(r > 0.0 ? r : 0.0);
    return denom > 0.0 ? clamp01(2.0 * s / denom) : 0.0;  // 0/0 only on a segment of zero density
}

// ---- Table reads, a vector of lanes at a time ----

// The two floats of each lane's 8-byte read (the first at the lower address), as doubles.
template <class D, class VU>
HWY_INLINE void split(D tag, VU u, hn::Vec<D>& first, hn::Vec<D>& second) {
    const hn::Rebind<std::uint32_t, D> du32;
    const hn::Rebind<float, D> df;
    first = hn::PromoteTo(tag, hn::BitCast(df, hn::TruncateTo(du32, u)));
    second = hn::PromoteTo(tag, hn::BitCast(df, hn::TruncateTo(du32, hn::ShiftRight<32>(u))));
}

// T[idx[k]] and T[idx[k] + 1] for the lanes k of a block, one 8-byte read each, as bits: a gather
// instruction does not pay on every CPU (AMD's are microcoded). at(du, k): the vector of lanes from k.
// Where vectors have a fixed size, a vector's reads are combined in registers, halves of halves: a
// vector loaded from the lanes' stores would wait for them (a load spanning several stores is not
// forwarded from them). Scalable vectors (SVE) and the one-lane target take a block's reads through
// memory.
#if !HWY_HAVE_SCALABLE && HWY_TARGET != HWY_SCALAR
template <class DU>
HWY_INLINE hn::Vec<DU> read_lanes(DU du, const float* t, const int* idx) {
    if constexpr (hn::MaxLanes(du) == 1) {
        std::uint64_t bits;
        std::memcpy(&bits, t + idx[0], sizeof bits);
        return hn::Set(du, bits);
    } else {
        constexpr int kHalf = static_cast<int>(hn::MaxLanes(du) / 2);
        const hn::Half<DU> dh;
        return hn::Combine(du, read_lanes(dh, t, idx + kHalf), read_lanes(dh, t, idx));
    }
}
struct Reads {
    const float* t;
    const int* idx;
    HWY_INLINE Reads(const float* table, const int* index, int) : t(table), idx(index) {}
    template <class DU>
    HWY_INLINE hn::Vec<DU> at(DU du, int k) const {
        return read_lanes(du, t, idx + k);
    }
};
#else
struct Reads {
    std::uint64_t bits[kBlock];
    HWY_INLINE Reads(const float* t, const int* idx, int m) {
        for (int k = 0; k < m; ++k) std::memcpy(bits + k, t + idx[k], sizeof *bits);
    }
    template <class DU>
    HWY_INLINE hn::Vec<DU> at(DU du, int k) const {
        return hn::LoadU(du, bits + k);
    }
};
#endif

// out[k] = (1 − w[k])·T[idx[k]] + w[k]·T[idx[k] + 1] for k < m (whole vectors): an entry blended between
// a lane's two slices.
template <class D>
HWY_INLINE void blend_reads(D tag, const float* t, const int* idx, const double* w, int m, double* out) {
    const hn::RebindToUnsigned<D> du;
    const Reads reads(t, idx, m);
    const hn::Vec<D> one = hn::Set(tag, 1.0);
    for (int k = 0; k < m; k += static_cast<int>(hn::Lanes(tag))) {
        hn::Vec<D> a, b;
        split(tag, reads.at(du, k), a, b);
        const hn::Vec<D> wk = hn::LoadU(tag, w + k);
        hn::StoreU(hn::Add(hn::Mul(hn::Sub(one, wk), a), hn::Mul(wk, b)), tag, out + k);
    }
}

// first[k] = T[idx[k]], second[k] = T[idx[k] + 1] for k < m: neighbouring samples of one row.
template <class D>
HWY_INLINE void pair_reads(D tag, const float* t, const int* idx, int m, double* first, double* second) {
    const hn::RebindToUnsigned<D> du;
    const Reads reads(t, idx, m);
    for (int k = 0; k < m; k += static_cast<int>(hn::Lanes(tag))) {
        hn::Vec<D> a, b;
        split(tag, reads.at(du, k), a, b);
        hn::StoreU(a, tag, first + k);
        hn::StoreU(b, tag, second + k);
    }
}

// ---- Slices ----

// A lane's slices: entry i is blended between slices lower and lower + 1 (kernels.h: stored side by
// side) with the weight w of the upper one.
struct Slices {
    int lower[kBlock];
    double w[kBlock];
};

// Where θ falls among the slices' θi: the lower slice is the number of θi[1 .. n−2] below θ (where
// std::lower_bound over them would stop, less one), its weight linear in θ between the two, clamped.
// NaN takes slice 0; a single slice has weight 0 (its copy as the upper one).
[[gnu::always_inline]] inline void slice_pass(const KernelTables& t, const double* theta, int m, Slices& s) {
    const int n = t.n_theta;
    for (int k = 0; k < m; ++k) s.lower[k] = 0, s.w[k] = 0.0;
    if (n < 2) return;
    for (int j = 1; j + 1 < n; ++j) {
        const double v = t.theta_i[j];
        for (int k = 0; k < m; ++k) s.lower[k] += v < theta[k];
    }
    for (int k = 0; k < m; ++k) {
        const int lo = s.lower[k];
        const double p0 = t.theta_i[lo], p1 = t.theta_i[lo + 1];
        s.w[k] = clamp01((theta[k] - p0) / (p1 - p0));
    }
}

// The grid cell (patch) holding a point of [0, 1]² and the point's position inside it; points outside
// are clamped onto the square, and the last row and column of samples belong to the patch before them.
struct Patch {
    int ix, iy;
    double fx, fy;
};
[[gnu::always_inline]] inline Patch locate(double x, double y, int rows, int cols) {
    const double sx = clamp01(x) * static_cast<double>(cols - 1), sy = clamp01(y) * static_cast<double>(rows - 1);
    const int ix = std::min(static_cast<int>(sx), cols - 2), iy = std::min(static_cast<int>(sy), rows - 2);
    return {ix, iy, sx - ix, sy - iy};
}

// Points of [0, 1]² and a warp's density there, for a block.
struct Points {
    double x[kBlock], y[kBlock], pdf[kBlock];
};

// Bilinear interpolation of one table (no slices) at the points.
template <class D>
[[gnu::always_inline]] inline void bilinear_pass(D tag, const GridTable& g, const double* x, const double* y, int m,
                                                 double* out) {
    int i0[kBlock], i1[kBlock];
    double fx[kBlock], fy[kBlock], v00[kBlock], v01[kBlock], v10[kBlock], v11[kBlock];
    for (int k = 0; k < m; ++k) {
        const Patch q = locate(x[k], y[k], g.rows, g.cols);
        i0[k] = q.iy * g.cols + q.ix, i1[k] = i0[k] + g.cols, fx[k] = q.fx, fy[k] = q.fy;
    }
    pair_reads(tag, g.values, i0, m, v00, v01);
    pair_reads(tag, g.values, i1, m, v10, v11);
    for (int k = 0; k < m; ++k) out[k] = lerp(lerp(v00[k], v01[k], fx[k]), lerp(v10[k], v11[k], fx[k]), fy[k]);
}

// The four corners of each point's patch in a stack of slices-innermost tables (rows × cols entries),
// blended between the lane's slices: d[0] at (ix, iy), d[1] at (ix + 1, iy), d[2] at (ix, iy + 1), d[3]
// at (ix + 1, iy + 1).
template <class D>
[[gnu::always_inline]] inline void corner_reads(D tag, const float* t, int cols, int stride, const Slices& s,
                                                const int* entry, int m, double (&d)[4][kBlock]) {
    int idx[4][kBlock];
    for (int k = 0; k < m; ++k) {
        const int e = entry[k] * stride + s.lower[k];
        idx[0][k] = e, idx[1][k] = e + stride, idx[2][k] = e + cols * stride, idx[3][k] = e + (cols + 1) * stride;
    }
    for (int c = 0; c < 4; ++c) blend_reads(tag, t, idx[c], s.w, m, d[c]);
}

// The warp's density at the points (integrating to 1 over [0, 1]²), blended between each lane's slices.
template <class D>
[[gnu::always_inline]] inline void density_pass(D tag, const WarpTables& w, const Slices& s, const double* px,
                                                const double* py, int m, double* out) {
    int entry[kBlock];
    double fx[kBlock], fy[kBlock], d[4][kBlock];
    for (int k = 0; k < m; ++k) {
        const Patch q = locate(px[k], py[k], w.rows, w.cols);
        entry[k] = q.iy * w.cols + q.ix, fx[k] = q.fx, fy[k] = q.fy;
    }
    corner_reads(tag, w.data, w.cols, w.stride, s, entry, m, d);
    for (int k = 0; k < m; ++k) out[k] = lerp(lerp(d[0][k], d[1][k], fx[k]), lerp(d[2][k], d[3][k], fx[k]), fy[k]);
}

// The inverse of the warp's sample (the CDF transform p ↦ (F(x | y), F(y))) and its density, at the
// points (x, y), blended between each lane's slices: the RGB tables are read at the VNDF warp's inverse
// of the microfacet normal, and pdf() needs the density there.
template <class D>
[[gnu::always_inline]] inline void invert_pass(D tag, const WarpTables& w, const Slices& s, const double* px,
                                               const double* py, int m, Points& out) {
    const int R = w.rows, C = w.cols, NC = C - 1, S = w.stride;
    const double width = 1.0 / static_cast<double>(C - 1), height = 1.0 / static_cast<double>(R - 1);
    int entry[kBlock], left[2][kBlock], end[2][kBlock], below[kBlock];
    double fx[kBlock], fy[kBlock], has_left[kBlock], has_below[kBlock];
    for (int k = 0; k < m; ++k) {
        const Patch q = locate(px[k], py[k], R, C);
        const int lo = s.lower[k], row0 = q.iy * NC, row1 = row0 + NC, l = q.ix > 0 ? q.ix - 1 : 0;
        entry[k] = q.iy * C + q.ix;
        left[0][k] = (row0 + l) * S + lo, left[1][k] = (row1 + l) * S + lo;
        end[0][k] = (row0 + NC - 1) * S + lo, end[1][k] = (row1 + NC - 1) * S + lo;
        below[k] = (q.iy > 0 ? q.iy - 1 : 0) * S + lo;
        fx[k] = q.fx, fy[k] = q.fy, has_left[k] = q.ix > 0 ? 1.0 : 0.0, has_below[k] = q.iy > 0 ? 1.0 : 0.0;
    }
    double d[4][kBlock], c_left[2][kBlock], r[2][kBlock], m_below[kBlock];
    corner_reads(tag, w.data, C, S, s, entry, m, d);
    for (int j = 0; j < 2; ++j) {
        blend_reads(tag, w.cond, left[j], s.w, m, c_left[j]);
        blend_reads(tag, w.cond, end[j], s.w, m, r[j]);
    }
    blend_reads(tag, w.marg, below, s.w, m, m_below);
    for (int k = 0; k < m; ++k) {
        // Density along the patch's left and right edges, at the point's height.
        const double c0 = lerp(d[0][k], d[2][k], fy[k]), c1 = lerp(d[1][k], d[3][k], fy[k]);
        // Conditional CDF of x: the patches to the left, interpolated between the patch's two rows, plus
        // the part of this patch; divided by the whole row's integral at this height.
        double x = partial_integral(fx[k], width, c0, c1);
        x += has_left[k] > 0.0 ? lerp(c_left[0][k], c_left[1][k], fy[k]) : 0.0;
        x /= lerp(r[0][k], r[1][k], fy[k]);
        // Marginal CDF of y: the rows of patches below, plus the part of this one.
        double y = partial_integral(fy[k], height, r[0][k], r[1][k]);
        y += has_below[k] > 0.0 ? m_below[k] : 0.0;
        out.x[k] = x, out.y[k] = y, out.pdf[k] = lerp(c0, c1, fx[k]);
    }
}

// The warp: points of [0, 1]² distributed with its density (blended between each lane's slices), from
// u in [0, 1]² (x and y each uniform), in place; the density at each point in pdf. The marginal CDF of y
// picks the row of patches, then the height inside it (along a patch row the marginal density, the row
// integral, is linear); the conditional CDF of x at that height (interpolated between the patch's rows)
// the column, then the position inside the patch, where the density is linear in x. Each CDF search
// finds the largest cell j with cdf(j) < u (0 if none), as a branch-free binary search in one pass per
// halving (the halvings depend on the cell count alone).
template <class D>
[[gnu::always_inline]] inline void sample_pass(D tag, const WarpTables& w, const Slices& s, int m, Points& p) {
    const int R = w.rows, C = w.cols, NC = C - 1, S = w.stride;
    const double width = 1.0 / static_cast<double>(C - 1), height = 1.0 / static_cast<double>(R - 1);
    double ux[kBlock], uy[kBlock], fy[kBlock], target[kBlock], v0[kBlock], v1[kBlock];
    int iy[kBlock], ix[kBlock], idx0[kBlock], idx1[kBlock];
    for (int k = 0; k < m; ++k) ux[k] = clamp01(p.x[k]), uy[k] = clamp01(p.y[k]), iy[k] = 0, ix[k] = 0;
    // Row: the marginal CDF at row j is marg[j − 1] (every probe j is at least 1).
    // below: the CDF at the row found, kept from the search's last move up (the read marg[iy − 1]), 0 when
    // it never moved; the same for the column below.
    double below[kBlock], before[kBlock];
    for (int k = 0; k < m; ++k) below[k] = before[k] = 0.0;
    for (int len = R - 1; len > 1;) {
        const int half = len / 2;
        for (int k = 0; k < m; ++k) idx0[k] = (iy[k] + half - 1) * S + s.lower[k];
        blend_reads(tag, w.marg, idx0, s.w, m, v0);
        for (int k = 0; k < m; ++k) {
            const bool up = v0[k] < uy[k];
            iy[k] = up ? iy[k] + half : iy[k];
            below[k] = up ? v0[k] : below[k];
        }
        len -= half;
    }
    for (int k = 0; k < m; ++k) idx0[k] = (iy[k] * NC + NC - 1) * S + s.lower[k], idx1[k] = idx0[k] + NC * S;  // row totals
    double r0[kBlock], r1[kBlock];
    blend_reads(tag, w.cond, idx0, s.w, m, r0);
    blend_reads(tag, w.cond, idx1, s.w, m, r1);
    for (int k = 0; k < m; ++k) {
        fy[k] = invert_partial_integral((uy[k] - below[k]) / height, r0[k], r1[k]);
        target[k] = ux[k] * lerp(r0[k], r1[k], fy[k]);
    }
    // Column: the conditional CDF at column j, between the patch's rows.
    for (int len = C - 1; len > 1;) {
        const int half = len / 2;
        for (int k = 0; k < m; ++k) idx0[k] = (iy[k] * NC + ix[k] + half - 1) * S + s.lower[k], idx1[k] = idx0[k] + NC * S;
        blend_reads(tag, w.cond, idx0, s.w, m, v0);
        blend_reads(tag, w.cond, idx1, s.w, m, v1);
        for (int k = 0; k < m; ++k) {
            const double v = lerp(v0[k], v1[k], fy[k]);
            const bool right = v < target[k];
            ix[k] = right ? ix[k] + half : ix[k];
            before[k] = right ? v : before[k];
        }
        len -= half;
    }
    int entry[kBlock];
    for (int k = 0; k < m; ++k) entry[k] = iy[k] * C + ix[k];
    double d[4][kBlock];
    corner_reads(tag, w.data, C, S, s, entry, m, d);
    for (int k = 0; k < m; ++k) {
        const double c0 = lerp(d[0][k], d[2][k], fy[k]), c1 = lerp(d[1][k], d[3][k], fy[k]);
        const double fx = invert_partial_integral((target[k] - before[k]) / width, c0, c1);
        p.x[k] = (static_cast<double>(ix[k]) + fx) * width;
        p.y[k] = (static_cast<double>(iy[k]) + fy[k]) * height;
        p.pdf[k] = lerp(c0, c1, fx);
    }
}

// ---- Pairs ----

// A block of direction pairs as arrays. Lanes that are not `ok`, and those past the block's end up to
// a whole number of vectors, hold the normal instead, so that every pass computes finite numbers and
// in-range indices there.
struct Pairs {
    double ax[kBlock], ay[kBlock], az[kBlock], bx[kBlock], by[kBlock], bz[kBlock];
    double ok[kBlock];  // 1 or 0, as a double: a select on bytes or a test of 64-bit integers between
                        // doubles does not vectorise (SSE2 has no 64-bit integer compare)
};

// m rounded up to whole vectors.
template <class D>
[[gnu::always_inline]] inline int whole(D tag, int m) {
    const int w = static_cast<int>(hn::Lanes(tag));
    return (m + w - 1) / w * w;
}

// Pairs [0, m) into the block, `a` the conditioning direction; ok where both are finite and above the
// horizon. Lanes [m, mw) as not ok.
[[gnu::always_inline]] inline void load_pairs(const Vec3* a, const Vec3* b, int m, int mw, Pairs& p) {
    for (int k = 0; k < m; ++k) {
        const Vec3& u = a[k];
        const Vec3& v = b[k];
        const bool fu = finite(u), fv = finite(v);
        const bool ok = (u.z > 0.0) & (v.z > 0.0) & fu & fv;
        p.ok[k] = ok ? 1.0 : 0.0;
        p.ax[k] = ok ? u.x : 0.0, p.ay[k] = ok ? u.y : 0.0, p.az[k] = ok ? u.z : 1.0;
        p.bx[k] = ok ? v.x : 0.0, p.by[k] = ok ? v.y : 0.0, p.bz[k] = ok ? v.z : 1.0;
    }
    for (int k = m; k < mw; ++k) p.ok[k] = 0.0, p.ax[k] = p.ay[k] = p.bx[k] = p.by[k] = 0.0, p.az[k] = p.bz[k] = 1.0;
}

// The microfacet normal between a direction a (the one the tables are conditioned on) and b, for a
// block: a's elevation and azimuth, m's unit coordinates (u_θm, and m's azimuth relative to a's, wrapped
// into [0, 1)), sinθm and a·m.
struct Geometry {
    double theta_a[kBlock], phi_a[kBlock];
    double um_x[kBlock], um_y[kBlock];
    double sin_m[kBlock], a_dot_m[kBlock];
};

[[gnu::always_inline]] inline void geometry_pass(const Pairs& p, int m, Geometry& g) {
    for (int k = 0; k < m; ++k) {
        const double ax = p.ax[k], ay = p.ay[k], az = p.az[k];
        const double sx = ax + p.bx[k], sy = ay + p.by[k], sz = az + p.bz[k];
        const double ra = std::sqrt(ax * ax + ay * ay), rs2 = sx * sx + sy * sy;
        const double rs = std::sqrt(rs2), len = std::sqrt(rs2 + sz * sz);
        const double phi_a = atan2_poly(ay, ax);
        // m's azimuth relative to a's, as u_φ, wrapped: φm − φa lies in (−2π, 2π).
        double u_phi = u_of_phi(atan2_poly(sy, sx) - phi_a);
        u_phi += u_phi < 0.0 ? 1.0 : 0.0;
        u_phi -= u_phi >= 1.0 ? 1.0 : 0.0;
        g.theta_a[k] = atan2_poly(ra, az), g.phi_a[k] = phi_a;
        g.um_x[k] = u_of_theta(atan2_poly(rs, sz)), g.um_y[k] = u_phi;
        g.sin_m[k] = rs / len;
        g.a_dot_m[k] = (ax * sx + ay * sy + az * sz) / len;
    }
}

// f for the block's pairs (a = wi, b = wo) into r, g, b (lanes [0, m); mw the lanes the passes run): the
// microfacet normal m = normalize(wi + wo) through the inverse of the VNDF warp at θi to a point of the
// RGB tables, scaled by D(m) / (4σ(wi)) with the file's jacobian flag, and by 1 / cosθo (the data hold
// f·cosθo).
template <class D>
[[gnu::always_inline]] inline void eval_block(D tag, const KernelTables& t, const Pairs& p, int m, int mw, double* out_r,
                                              double* out_g, double* out_b) {
    Geometry g;
    Slices s;
    Points pts;
    geometry_pass(p, mw, g);
    slice_pass(t, g.theta_a, mw, s);
    invert_pass(tag, t.vndf, s, g.um_x, g.um_y, mw, pts);
    double scale[kBlock];
    for (int k = 0; k < mw; ++k) scale[k] = 1.0 / p.bz[k];
    if (t.jacobian) {
        double d[kBlock], sigma[kBlock], ui_x[kBlock], ui_y[kBlock];
        for (int k = 0; k < mw; ++k) ui_x[k] = u_of_theta(g.theta_a[k]), ui_y[k] = u_of_phi(g.phi_a[k]);
        bilinear_pass(tag, t.ndf, g.um_x, g.um_y, mw, d);
        bilinear_pass(tag, t.sigma, ui_x, ui_y, mw, sigma);
        for (int k = 0; k < mw; ++k) scale[k] *= d[k] / (4.0 * sigma[k]);
    }
    // RGB: each point's three channels (kernels.h: channel by channel, slices innermost), the patch's
    // four corners blended between the lane's slices.
    const int R = t.rgb_rows, C = t.rgb_cols, S = t.vndf.stride;
    int entry[kBlock];
    double fx[kBlock], fy[kBlock], d[3][4][kBlock];
    for (int k = 0; k < mw; ++k) {
        const Patch q = locate(pts.x[k], pts.y[k], R, C);
        entry[k] = (q.iy * C + q.ix) * 3, fx[k] = q.fx, fy[k] = q.fy;
    }
    for (int c = 0; c < 3; ++c) {
        int idx[4][kBlock];
        for (int k = 0; k < mw; ++k) {
            const int e = (entry[k] + c) * S + s.lower[k];
            idx[0][k] = e, idx[1][k] = e + 3 * S, idx[2][k] = e + 3 * C * S, idx[3][k] = e + 3 * (C + 1) * S;
        }
        for (int j = 0; j < 4; ++j) blend_reads(tag, t.rgb, idx[j], s.w, mw, d[c][j]);
    }
    double* out[3] = {out_r, out_g, out_b};
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < m; ++k) {
            const double v = lerp(lerp(d[c][0][k], d[c][1][k], fx[k]), lerp(d[c][2][k], d[c][3][k], fx[k]), fy[k]) * scale[k];
            // A zero sigma, an empty VNDF row or a cosθo so small that f overflows would give Inf or NaN.
            const bool fv = finite(v);
            out[c][k] = ((p.ok[k] > 0.0) & fv) ? v : 0.0;
        }
}

template <class D>
[[gnu::always_inline]] inline void eval_passes(D tag, const KernelTables& t, const Vec3* wi, const Vec3* wo, Rgb* out,
                                               std::size_t n) {
    Pairs p;
    double r[kBlock], g[kBlock], b[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const int m = static_cast<int>(std::min<std::size_t>(kBlock, n - start)), mw = whole(tag, m);
        load_pairs(wi + start, wo + start, m, mw, p);
        eval_block(tag, t, p, m, mw, r, g, b);
        for (int k = 0; k < m; ++k) out[start + k] = {r[k], g[k], b[k]};
    }
}

// dω/du_m for the direction reflected about m: dω_m/du_m = (π/2 · 2u_θ dθ)(2π dφ) sinθm = 2π²·u_θ·sinθm,
// times dω/dω_m = 4 (w·m). 0 at the pole and for back-facing m, where no density is defined.
[[gnu::always_inline]] inline double solid_angle_per_unit_square(double u_theta, double sin_m, double w_dot_m) {
    const double j = 2.0 * kPi * kPi * u_theta * sin_m * 4.0 * w_dot_m;
    return j > 0.0 ? j : 0.0;
}

// The density of sample() (rgl.h): the warps conditioned on wo (the block's a), at the point the
// luminance warp must have produced (the VNDF warp's inverse of m), over the Jacobian.
template <class D>
[[gnu::always_inline]] inline void pdf_passes(D tag, const KernelTables& t, const Vec3* wo, const Vec3* wi, double* out,
                                              std::size_t n) {
    Pairs p;
    Geometry g;
    Slices s;
    Points q;
    double lum[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const int m = static_cast<int>(std::min<std::size_t>(kBlock, n - start)), mw = whole(tag, m);
        load_pairs(wo + start, wi + start, m, mw, p);
        geometry_pass(p, mw, g);
        slice_pass(t, g.theta_a, mw, s);
        invert_pass(tag, t.vndf, s, g.um_x, g.um_y, mw, q);
        if (t.luminance.data)
            density_pass(tag, t.luminance, s, q.x, q.y, mw, lum);
        else
            for (int k = 0; k < mw; ++k) lum[k] = 1.0;
        for (int k = 0; k < m; ++k) {
            const double jacobian = solid_angle_per_unit_square(g.um_x[k], g.sin_m[k], g.a_dot_m[k]);
            const double pdf = q.pdf[k] * lum[k] / jacobian;
            const bool fp = finite(pdf);
            out[start + k] = ((p.ok[k] > 0.0) & (q.pdf[k] > 0.0) & (jacobian > 0.0) & fp) ? pdf : 0.0;
        }
    }
}

// sample(): the luminance warp (conditioned on wo's θ) maps u to a point of the VNDF warp's square, the
// VNDF warp maps that to m in unit coordinates, and wo is reflected about m (rgl.h); u in Mitsuba's
// order, its sample2 swapped. The weight is f(wi, wo)·cosθi / pdf, f from the eval block.
template <class D>
[[gnu::always_inline]] inline void sample_passes(D tag, const KernelTables& t, const Vec3* wo, const std::array<double, 2>* u,
                                                 BrdfSample* out, std::size_t n) {
    Pairs p, e;
    Slices s;
    Points q;
    double theta_o[kBlock], cos_o[kBlock], sin_o[kBlock], pdf_l[kBlock];
    double r[kBlock], g[kBlock], b[kBlock], pdf[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const int m = static_cast<int>(std::min<std::size_t>(kBlock, n - start)), mw = whole(tag, m);
        for (int k = 0; k < m; ++k) {
            const Vec3& w = wo[start + k];
            const double u1 = u[start + k][0], u2 = u[start + k][1];
            // Brdf::can_draw, branch-free.
            const bool ok = (w.z > 0.0) & (u1 >= 0.0) & (u1 < 1.0) & (u2 >= 0.0) & (u2 < 1.0) & finite(w);
            p.ok[k] = ok ? 1.0 : 0.0;
            p.bx[k] = ok ? w.x : 0.0, p.by[k] = ok ? w.y : 0.0, p.bz[k] = ok ? w.z : 1.0;
            q.x[k] = ok ? u2 : 0.0, q.y[k] = ok ? u1 : 0.0;
        }
        for (int k = m; k < mw; ++k) p.ok[k] = 0.0, p.bx[k] = p.by[k] = 0.0, p.bz[k] = 1.0, q.x[k] = q.y[k] = 0.0;
        for (int k = 0; k < mw; ++k) {
            const double x = p.bx[k], y = p.by[k], z = p.bz[k];
            const double ro = std::sqrt(x * x + y * y);
            theta_o[k] = atan2_poly(ro, z);
            // wo's azimuth as a rotation; at the pole std::atan2's (0 or π by the signs of the zeros).
            cos_o[k] = ro > 0.0 ? x / ro : std::copysign(1.0, x), sin_o[k] = ro > 0.0 ? y / ro : 0.0;
        }
        slice_pass(t, theta_o, mw, s);
        if (t.luminance.data) {
            sample_pass(tag, t.luminance, s, mw, q);
            for (int k = 0; k < mw; ++k) pdf_l[k] = q.pdf[k];
        } else {
            for (int k = 0; k < mw; ++k) pdf_l[k] = 1.0;
        }
        sample_pass(tag, t.vndf, s, mw, q);
        for (int k = 0; k < mw; ++k) {
            // m from its unit coordinates: θm = u_θ²·π/2, azimuth (2u_φ − 1)π from wo's.
            const ::brdfz::detail::SinCos2 th = ::brdfz::detail::sincos_half_turn(q.x[k] * q.x[k] * (kPi / 2.0));
            const double phi = (2.0 * q.y[k] - 1.0) * kPi;
            const ::brdfz::detail::SinCos2 ph = ::brdfz::detail::sincos_half_turn(std::fabs(phi));
            const double sin_p = std::copysign(ph.s, phi);
            const double mx = th.s * (cos_o[k] * ph.c - sin_o[k] * sin_p), my = th.s * (sin_o[k] * ph.c + cos_o[k] * sin_p);
            const double mz = th.c;
            const double wo_dot_m = p.bx[k] * mx + p.by[k] * my + p.bz[k] * mz;
            const double jacobian = solid_angle_per_unit_square(q.x[k], th.s, wo_dot_m);
            const double d = jacobian > 0.0 ? pdf_l[k] * q.pdf[k] / jacobian : 0.0;
            const double wx = 2.0 * wo_dot_m * mx - p.bx[k], wy = 2.0 * wo_dot_m * my - p.by[k],
                         wz = 2.0 * wo_dot_m * mz - p.bz[k];
            // Brdf::usable: a back-facing m reflects wo below the horizon with pdf 0.
            const bool ok = (p.ok[k] > 0.0) & (wz > 0.0) & (d > 0.0) & (d < kInf);
            pdf[k] = d;
            e.ax[k] = ok ? wx : 0.0, e.ay[k] = ok ? wy : 0.0, e.az[k] = ok ? wz : 1.0;
            e.bx[k] = ok ? p.bx[k] : 0.0, e.by[k] = ok ? p.by[k] : 0.0, e.bz[k] = ok ? p.bz[k] : 1.0;
            e.ok[k] = ok ? 1.0 : 0.0;
        }
        eval_block(tag, t, e, m, mw, r, g, b);
        for (int k = 0; k < m; ++k) {
            BrdfSample& o = out[start + k];
            if (!(e.ok[k] > 0.0)) {
                o = {};
                continue;
            }
            const double c = e.az[k] / pdf[k];
            o = {{e.ax[k], e.ay[k], e.az[k]}, pdf[k], {r[k] * c, g[k] * c, b[k] * c}};
        }
    }
}

// Fewer pairs than a vector holds (one call at a time) run one lane: the same operations, so the same
// bits, without computing the unused lanes.
using Full = hn::ScalableTag<double>;
using One = hn::CappedTag<double, 1>;

}  // namespace

void EvalPairs(const KernelTables& t, const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) {
    if (n < hn::Lanes(Full())) eval_passes(One(), t, wi, wo, out, n);
    else eval_passes(Full(), t, wi, wo, out, n);
}

void PdfPairs(const KernelTables& t, const Vec3* wo, const Vec3* wi, double* out, std::size_t n) {
    if (n < hn::Lanes(Full())) pdf_passes(One(), t, wo, wi, out, n);
    else pdf_passes(Full(), t, wo, wi, out, n);
}

void SamplePairs(const KernelTables& t, const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out,
                 std::size_t n) {
    if (n < hn::Lanes(Full())) sample_passes(One(), t, wo, u, out, n);
    else sample_passes(Full(), t, wo, u, out, n);
}

void SampleWarp(const WarpTables& w, int slice, double* x, double* y, double* pdf, std::size_t n) {
    const Full tag;
    Slices s;
    Points p;
    for (int k = 0; k < kBlock; ++k) s.lower[k] = slice, s.w[k] = 0.0;
    for (std::size_t start = 0; start < n; start += kBlock) {
        const int m = static_cast<int>(std::min<std::size_t>(kBlock, n - start)), mw = whole(tag, m);
        for (int k = 0; k < mw; ++k) p.x[k] = k < m ? x[start + k] : 0.0, p.y[k] = k < m ? y[start + k] : 0.0;
        sample_pass(tag, w, s, mw, p);
        for (int k = 0; k < m; ++k) x[start + k] = p.x[k], y[start + k] = p.y[k], pdf[start + k] = p.pdf[k];
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace brdfz::rgl::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "hwy_dispatch.h"

namespace brdfz::rgl::detail {

void sample_warp(const WarpTables& w, int slice, double* x, double* y, double* pdf, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(SampleWarp);
    builds.at(::brdfz::detail::simd_level())(w, slice, x, y, pdf, n);
}

void eval_pairs(Simd simd, const KernelTables& t, const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(EvalPairs);
    builds.at(simd)(t, wi, wo, out, n);
}

void pdf_pairs(Simd simd, const KernelTables& t, const Vec3* wo, const Vec3* wi, double* out, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(PdfPairs);
    builds.at(simd)(t, wo, wi, out, n);
}

void sample_pairs(Simd simd, const KernelTables& t, const Vec3* wo, const std::array<double, 2>* u,
                  BrdfSample* out, std::size_t n) {
    static const auto builds = BRDFZ_HWY_BUILDS(SamplePairs);
    builds.at(simd)(t, wo, u, out, n);
}

}  // namespace brdfz::rgl::detail
#endif  // HWY_ONCE
