// A Rusinkiewicz grid's lookup arithmetic: direction pair -> bin coordinates -> nearest bin or the
// interpolation corners -> a channel blend that skips invalid samples. The one scalar source of it:
// the core's table and factor kernels (lib/src/detail/table_lookup.h, the batch kernels built on it)
// and brdfz::runtime call these same functions, so a lookup gives the same bits in both.
//
// The functions take any grid type G with the members of the core's GridSpec they read: int
// n_theta_h, n_theta_d, n_phi_d; double theta_h_warp, theta_d_warp; sample_offset(), bilateral(),
// full_circle() and index(ih, id, ip) (brdfz/table.h documents the axes; kernels::Grid below is the
// runtime's).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::runtime::kernels {

// The runtime's grid (formats/SPEC.md, the runtime layout's GRID section).
struct Grid {
    enum class Axis { Reciprocal = 0, None = 1, Bilateral = 2 };  // the φd axis (table.h's Symmetry)
    int n_theta_h = 0, n_theta_d = 0, n_phi_d = 0;
    bool centre = true;  // samples at bin centres (else at bin starts)
    double theta_d_warp = 0.0;
    Axis phi_d_axis = Axis::Reciprocal;
    double theta_h_warp = 0.0;
    double sample_offset() const { return centre ? 0.5 : 0.0; }
    bool bilateral() const { return phi_d_axis == Axis::Bilateral; }
    bool full_circle() const { return phi_d_axis == Axis::None; }
    std::size_t index(int ih, int id, int ip) const {
        return static_cast<std::size_t>(ip) +
               static_cast<std::size_t>(n_phi_d) * (id + static_cast<std::size_t>(n_theta_d) * ih);
    }
    std::size_t bins() const { return static_cast<std::size_t>(n_theta_h) * n_theta_d * n_phi_d; }
};

// The axes' forward maps, angle -> continuous bin coordinate, in MERL's operation order (so that floor()
// matches its published lookup bit for bit).
namespace axis {
inline double theta_h_to_u(double theta_h, int n) { return theta_h <= 0.0 ? 0.0 : std::sqrt(theta_h / (kPi / 2.0) * n * n); }
// The θh axis warped by a specular peak's scale s > 0 (radians): u/n = θh/(θh + s) · (π/2 + s)/(π/2), about
// n/s bins per radian at the pole (the square-root axis: infinitely many at θh = 0, few a degree away);
// s = 0 is the square-root axis.
inline double warped_theta_h_to_u(double theta_h, int n, double s) {
    return theta_h / (theta_h + s) * ((kPi / 2.0 + s) / (kPi / 2.0)) * n;
}
inline double theta_h_to_u(double theta_h, int n, double s) {
    if (s == 0.0) return theta_h_to_u(theta_h, n);
    return theta_h <= 0.0 ? 0.0 : warped_theta_h_to_u(theta_h, n, s);
}
inline double theta_d_to_u(double theta_d, int n) { return theta_d / (kPi * 0.5) * n; }
// The warped θd axis, w in [0, 0.95]: u/n = (1 − w)·θd/(π/2) + w·(1 − cos θd); w = 0 is the linear axis.
inline double theta_d_to_u(double theta_d, int n, double w) {
    if (w == 0.0) return theta_d_to_u(theta_d, n);
    return ((1.0 - w) * theta_d * (2.0 / kPi) + w * (1.0 - std::cos(theta_d))) * n;
}
// φd in (-π, π] folded to [0, π] by reciprocity.
inline double phi_d_to_u(double phi_d, int n) {
    if (phi_d < 0.0) phi_d += kPi;
    return phi_d / kPi * n;
}
// φd folded by the mirror: |φd|.
inline double bilateral_phi_d_to_u(double phi_d, int n) { return std::fabs(phi_d) / kPi * n; }
// φd on the full circle [0, 2π].
inline double full_phi_d_to_u(double phi_d, int n) {
    if (phi_d < 0.0) phi_d += 2.0 * kPi;
    return phi_d / (2.0 * kPi) * n;
}
}  // namespace axis

// Continuous bin coordinates (θh, θd, φd) of a direction pair on a grid.
struct BinCoords {
    double uh, ud, up;
};

// MERL's arithmetic: what nearest lookup must match bit for bit.
template <typename G>
inline BinCoords bin_coords(const G& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 h = half_vector(wi, wo);
    const Vec3 d = difference_vector(wi, half_frame(h));
    const double phi = std::atan2(d.y, d.x);
    return {axis::theta_h_to_u(elevation(h), g.n_theta_h, g.theta_h_warp),
            axis::theta_d_to_u(elevation(d), g.n_theta_d, g.theta_d_warp),
            g.full_circle() ? axis::full_phi_d_to_u(phi, g.n_phi_d)
            : g.bilateral() ? axis::bilateral_phi_d_to_u(phi, g.n_phi_d)
                            : axis::phi_d_to_u(phi, g.n_phi_d)};
}

// bin_coords without asin, atan2 or a normalisation: every angle is an arctangent of two lengths
// in one (arbitrary) scale, from s = wi + wo, the unnormalised half vector:
//   θh = atan(|s_xy| / s_z),  θd = atan(|wi × s| / wi·s),
//   φd = atan(d_y / d_x) with d_x, d_y (half_frame's) both multiplied by |s|·|s_xy| > 0 (phi_d_coord).
// Within 5e-8 bins of bin_coords (angles to 2.2e-10 relative; rounding ~1e-16 / sinθd in φd), except
// where φd is ill-conditioned (θh or θd below 1e-6): there up is kIllConditioned, beyond any grid, for
// the callers to fall back to bin_coords. Branch-free, so the compiler vectorises it across pairs.
constexpr double kIllConditioned = 1e300;

// θd's bin coordinate on the grid's axis, from θd and cosθd: the warped axis is a select, so the linear
// axis stays exact and the callers' loops stay branch-free.
template <bool Fused = false, typename G>
[[gnu::always_inline]] inline double theta_d_coord(const G& g, double theta_d, double cos_d) {
    const double w = g.theta_d_warp;
    const double ud_linear = theta_d * (2.0 / kPi) * g.n_theta_d;
    const double ud_warped = madd<Fused>(w, 1.0 - cos_d, (1.0 - w) * theta_d * (2.0 / kPi)) * g.n_theta_d;
    return w == 0.0 ? ud_linear : ud_warped;
}

// The θh axes a coordinate loop handles: either, by a select per pair, or the square-root one alone, for
// batch loops that make the choice once (the warped axis's division costs them a few per cent).
enum class ThetaHAxes { Any, SquareRoot };

// θh's bin coordinate on the grid's axis: the warped axis a select, as θd's.
template <ThetaHAxes Axes = ThetaHAxes::Any, typename G>
[[gnu::always_inline]] inline double theta_h_coord(const G& g, double theta_h) {
    const double uh_root = std::sqrt(theta_h * (2.0 / kPi)) * g.n_theta_h;
    if constexpr (Axes == ThetaHAxes::SquareRoot) return uh_root;
    const double s = g.theta_h_warp;
    const double uh_warped = axis::warped_theta_h_to_u(theta_h, g.n_theta_h, s);
    return s == 0.0 ? uh_root : uh_warped;
}

// φd's bin coordinate from (y, x), d_y and d_x in any one positive scale: fast_half_turn_angle folds
// the angle into [0, π] (a reciprocal grid's axis); the full circle adds π where d_y < 0; the mirror
// fold takes |d_y|, so |φd|. Selects, not branches, and on a reciprocal grid the arithmetic of the
// folded axis exactly.
template <bool Fused = false, typename G>
[[gnu::always_inline]] inline double phi_d_coord(const G& g, double y, double x) {
    const bool full = g.full_circle();
    // |d_y| by masking its sign bit (all bits kept on the other axes): one AND per pair, not a select.
    const std::uint64_t keep = g.bilateral() ? ~(std::uint64_t{1} << 63) : ~std::uint64_t{0};
    const double folded = bits_as<double>(bits_as<std::uint64_t>(y) & keep);
    const double phi = fast_half_turn_angle<Fused>(folded, x) + ((full & (y < 0.0)) ? kPi : 0.0);
    return phi * (full ? 0.5 / kPi : 1.0 / kPi) * g.n_phi_d;
}

// dot(a, b), (a_x b_x + a_y b_y) + a_z b_z, in fused multiply-adds where Fused, else dot itself (math.h,
// madd: why the unfused forms keep the callers' own expressions).
template <bool Fused>
[[gnu::always_inline]] inline double dot_madd(const Vec3& a, const Vec3& b) {
    if constexpr (Fused)
        return std::fma(a.z, b.z, std::fma(a.y, b.y, a.x * b.x));
    else
        return dot(a, b);
}

// Always inlined: a call per pair would keep the callers' coordinate loops from vectorising. Fused
// (math.h, madd): the products and sums as fused multiply-adds, for a build of a CPU with FMA.
template <ThetaHAxes Axes = ThetaHAxes::Any, bool Fused = false, typename G>
[[gnu::always_inline]] inline BinCoords fast_bin_coords(const G& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 s = wi + wo;
    const double rxy2 = madd<Fused>(s.y, s.y, s.x * s.x);
    const double rxy = std::sqrt(rxy2);
    const double len = std::sqrt(madd<Fused>(s.z, s.z, rxy2));
    const Vec3 cr{nmadd<Fused>(wi.z, s.y, wi.y * s.z), nmadd<Fused>(wi.x, s.z, wi.z * s.x),
                  nmadd<Fused>(wi.y, s.x, wi.x * s.y)};
    const double sin_d = std::sqrt(dot_madd<Fused>(cr, cr));  // sinθd·|s|
    const double theta_h = fast_half_turn_angle<Fused>(rxy, s.z);
    const double theta_d = fast_half_turn_angle<Fused>(sin_d, dot_madd<Fused>(wi, s));
    const double dx = nmadd<Fused>(wi.z, rxy2, s.z * madd<Fused>(wi.y, s.y, wi.x * s.x));
    const double up = phi_d_coord<Fused>(g, -cr.z * len, dx);
    constexpr double kMinSin = 1e-6;
    const bool sure = (rxy > kMinSin * len) & (sin_d > kMinSin * len);
    return {theta_h_coord<Axes>(g, theta_h), theta_d_coord<Fused>(g, theta_d, dot_madd<Fused>(wi, s) / len),
            std::max(up, sure ? 0.0 : kIllConditioned)};
}

// Clamp to [0, hi] with comparisons, NaN to 0: std::fmin/fmax are out-of-line libm calls here.
inline double clamp0(double u, double hi) { return u > 0.0 ? (u < hi ? u : hi) : 0.0; }
inline int bin_of(double u, int n) { return static_cast<int>(clamp0(u, n - 1.0)); }

// The bin of a fast_bin_coords coordinate, in `bin`; true when the coordinate is far enough from a bin
// edge (0 and n included) for that bin to be bin_coords' bin. False for NaN and kIllConditioned.
inline bool clear_bin(double u, int n, int& bin) {
    constexpr double kMargin = 1e-6;  // 20x fast_bin_coords' error bound (5e-8 bins)
    const double c = clamp0(u, n);
    bin = static_cast<int>(c);
    const double frac = c - bin;
    return static_cast<bool>((frac > kMargin) & (frac < 1.0 - kMargin) & (bin < n));  // &, not &&: no branch
}

// Out of line: rare, and it would crowd the hot loop.
template <typename G>
[[gnu::noinline]] inline std::size_t exact_nearest_bin(const G& g, const Vec3& wi, const Vec3& wo) {
    const BinCoords c = bin_coords(g, wi, wo);
    return g.index(bin_of(c.uh, g.n_theta_h), bin_of(c.ud, g.n_theta_d), bin_of(c.up, g.n_phi_d));
}

// The nearest bin given the pair's fast coordinates.
template <typename G>
inline std::size_t nearest_bin(const G& g, const BinCoords& c, const Vec3& wi, const Vec3& wo) {
    int ih, id, ip;
    const bool ch = clear_bin(c.uh, g.n_theta_h, ih), cd = clear_bin(c.ud, g.n_theta_d, id),
               cp = clear_bin(c.up, g.n_phi_d, ip);
    return (ch & cd & cp) ? g.index(ih, id, ip) : exact_nearest_bin(g, wi, wo);
}

// Two neighbouring samples along a clamped axis and the weight of the second.
struct Span {
    int i0, i1;
    double t;
};

inline Span clamped_span(double c, int n) {
    c = clamp0(c, n - 1.0);
    const int i0 = static_cast<int>(c);
    const int i1 = i0 + 1 < n ? i0 + 1 : i0;
    return {i0, i1, c - i0};
}

// c is in [-0.5, n] (φd over the axis' range, minus the sample offset) or NaN: one wrap, not fmod.
inline Span periodic_span(double c, int n) {
    if (c < 0.0) c += n;
    if (!(c < n)) c = 0.0;  // c == n after rounding, or NaN
    const int i0 = static_cast<int>(c);
    return {i0, i0 + 1 < n ? i0 + 1 : 0, c - i0};
}

// φd's two samples: around the circle where the axis is periodic (reciprocal: φd ~ φd + π; none: the
// full circle); on the bilateral axis, whose ends 0 and π are mirror planes, clamped, which is the
// reflection there: a sample's mirror image about an end is the end sample itself (bin centres) or
// lies as far beyond the end as the sample inside it (bin starts), so the lookup is flat at the ends.
template <typename G>
inline Span phi_d_span(const G& g, double c) {
    return g.bilateral() ? clamped_span(c, g.n_phi_d) : periodic_span(c, g.n_phi_d);
}

struct Corners {
    Span h, d, p;
};

// Linear lookup uses the fast coordinates (5e-8 bins off: ~1e-9 relative in the result) except where
// they flagged φd as ill-conditioned.
template <typename G>
inline Corners linear_corners(const G& g, BinCoords c, const Vec3& wi, const Vec3& wo) {
    if (__builtin_expect(!(c.up <= g.n_phi_d), 0))  // kIllConditioned or NaN
        c = bin_coords(g, wi, wo);
    const double off = g.sample_offset();
    return {clamped_span(c.uh - off, g.n_theta_h), clamped_span(c.ud - off, g.n_theta_d), phi_d_span(g, c.up - off)};
}

// The eight corners of a linear lookup in the blends' order: visit(bin, w) with each corner's bin and
// weight, the same products in the same order for every blend, so that they give the same bits.
template <typename G, typename Visit>
[[gnu::always_inline]] inline void for_each_corner(const G& g, const Corners& k, Visit&& visit) {
    for (int a = 0; a < 2; ++a) {
        const int ih = a ? k.h.i1 : k.h.i0;
        const double wa = a ? k.h.t : 1.0 - k.h.t;
        for (int b = 0; b < 2; ++b) {
            const int id = b ? k.d.i1 : k.d.i0;
            const double wb = wa * (b ? k.d.t : 1.0 - k.d.t);
            const std::size_t row = g.index(ih, id, 0);  // the index is linear in φd's
            for (int p = 0; p < 2; ++p) visit(row + (p ? k.p.i1 : k.p.i0), wb * (p ? k.p.t : 1.0 - k.p.t));
        }
    }
}

// The blend of the eight corners, channel by channel: invalid samples (NaN) contribute neither value nor
// weight; a pair whose corners are all invalid is 0. Values provides load(bin, float v[3]). The scalar
// reference of the vector builds (lib/runtime/src/blend_lanes-inl.h), which give its bits.
template <typename G, typename Values>
inline void blend_linear(const G& g, const Values& values, const Corners& k, double f[3]) {
    double sum[3] = {0.0, 0.0, 0.0}, wsum[3] = {0.0, 0.0, 0.0};
    for_each_corner(g, k, [&](std::size_t bin, double w) {
        float v[3];
        values.load(bin, v);
        for (int c = 0; c < 3; ++c) {
            const double x = v[c];
            sum[c] += x == x ? w * x : 0.0;
            wsum[c] += x == x ? w : 0.0;
        }
    });
    for (int c = 0; c < 3; ++c) f[c] = wsum[c] > 0.0 ? sum[c] / wsum[c] : 0.0;
}

// blend_linear as a blend policy, which the table kernels take: this one, or a target's vector build
// (lib/runtime/src/blend_lanes-inl.h, BlendLanes).
struct ScalarBlend {
    template <typename G, typename Values>
    static void blend(const G& g, const Values& values, const Corners& k, double f[3]) {
        blend_linear(g, values, k, f);
    }
};

// Whether a Values policy's bins are three floats in memory, readable as four (floats(bin); the core's
// tables pad their storage): the vector builds then load a corner as one vector instead of lane by lane.
template <typename Values, typename = void>
struct FloatBins : std::false_type {};
template <typename Values>
struct FloatBins<Values, std::void_t<decltype(std::declval<const Values&>().floats(std::size_t{}))>> : std::true_type {};

// The nearest sample's channels, 0 for an invalid one.
template <typename Values>
inline void read_nearest(const Values& values, std::size_t bin, double f[3]) {
    float v[3];
    values.load(bin, v);
    for (int c = 0; c < 3; ++c) f[c] = v[c] == v[c] ? v[c] : 0.0;
}

}  // namespace brdfz::runtime::kernels
