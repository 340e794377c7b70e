#include "brdfz/repr/factored.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <type_traits>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/fast_math.h"
#include "detail/fit_points.h"
#include "detail/grid_sweep.h"
#include "detail/simd.h"
#include "detail/table_lookup.h"

namespace brdfz {
namespace {

// ---------------------------------------------------------------------------------------------
// Names

template <typename E>
struct Named {
    E value;
    const char* name;
};

constexpr Named<FactorMethod> kMethods[] = {{FactorMethod::Svd, "svd"}, {FactorMethod::Nmf, "nmf"}};
constexpr Named<FactorSpace> kSpaces[] = {
    {FactorSpace::Linear, "linear"}, {FactorSpace::Cos, "cos"}, {FactorSpace::Log, "log"}, {FactorSpace::Cbrt, "cbrt"}};
constexpr Named<FactorLayout> kLayouts[] = {{FactorLayout::HxDP, "h_dp"}, {FactorLayout::HDxP, "hd_p"}};
constexpr Named<FactorColour> kColours[] = {{FactorColour::Separate, "separate"}, {FactorColour::Shared, "shared"}};
constexpr Named<FactorFit> kFits[] = {{FactorFit::Samples, "samples"}, {FactorFit::LeastSquares, "lsq"}};
constexpr Named<FactorDtype> kDtypes[] = {{FactorDtype::F32, "f32"}, {FactorDtype::F16, "f16"}};

template <typename E, std::size_t N>
const char* name_of(const Named<E> (&table)[N], E value) {
    for (const Named<E>& n : table)
        if (n.value == value) return n.name;
    return "?";
}

template <typename E, std::size_t N>
E parse(const Named<E> (&table)[N], const std::string& name, const char* what) {
    std::string known;
    for (const Named<E>& n : table) {
        if (name == n.name) return n.value;
        known += (known.empty() ? "" : ", ") + std::string(n.name);
    }
    throw ValueError(std::string("unknown factorisation ") + what + " '" + name + "' (expected " + known + ")");
}

// ---------------------------------------------------------------------------------------------
// Transform spaces

double to_space(FactorSpace s, double f) {
    switch (s) {
        case FactorSpace::Log: return std::log1p(f);
        case FactorSpace::Cbrt: return std::cbrt(f);
        default: return f;
    }
}

// The value for a reconstruction y (already at most the ceiling); y < 0 (possible for svd) gives 0.
// No libm call, so the loop below vectorises. A float y (eval's blend, ~1e-7 from exact already)
// takes the float expm1, a double y (reconstruct) the double one; the cube is in double, where the
// ceiling's cube cannot overflow.
template <FactorSpace S, typename T>
inline double from_space(T y) {
    const T p = y > T(0) ? y : T(0);  // NaN cannot occur: factors are finite
    if constexpr (S == FactorSpace::Log) {
        if constexpr (std::is_same_v<T, float>)
            return detail::expm1_nonneg_f(p);
        else
            return detail::expm1_nonneg(p);
    } else if constexpr (S == FactorSpace::Cbrt) {
        const double q = p;
        return q * q * q;
    } else {
        return p;
    }
}

// out[i] = the value of y[i], counting the negatives clamped (in a T: GCC vectorises that sum
// with the loop, not an integer one).
template <FactorSpace S, typename T>
void from_space_n(const T* y, double* out, std::size_t n, std::uint64_t& clamped) {
    T count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        count += y[i] < T(0) ? T(1) : T(0);
        out[i] = from_space<S>(y[i]);
    }
    clamped += static_cast<std::uint64_t>(count);
}

template <typename T>
void from_space_n(FactorSpace s, const T* y, double* out, std::size_t n, std::uint64_t& clamped) {
    switch (s) {
        case FactorSpace::Log: return from_space_n<FactorSpace::Log>(y, out, n, clamped);
        case FactorSpace::Cbrt: return from_space_n<FactorSpace::Cbrt>(y, out, n, clamped);
        default: return from_space_n<FactorSpace::Linear>(y, out, n, clamped);
    }
}

// ---------------------------------------------------------------------------------------------
// Evaluation: interpolation corners in factor rows and columns

// The blend's SIMD vectors (GCC vector extensions): 4 floats (SSE) or 8 (AVX). The kernel below is
// always inlined into its two entry points, so no vector crosses a call and the ABI note GCC warns
// about for 8-float vectors outside AVX code does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
typedef float Float4 __attribute__((vector_size(16)));
typedef float Float8 __attribute__((vector_size(32)));
template <int W>
struct FloatVector;
template <>
struct FloatVector<4> {
    using type = Float4;
};
template <>
struct FloatVector<8> {
    using type = Float8;
};
template <int W>
using FloatV = typename FloatVector<W>::type;

template <typename V>
[[gnu::always_inline]] inline V load(const float* p) {
    V v;
    std::memcpy(&v, p, sizeof v);  // unaligned: one movups
    return v;
}

// Floats per blend step of each kernel; rows are zero-padded to a multiple of it.
constexpr std::size_t lanes(detail::Simd s) { return s == detail::Simd::Avx2Fma ? 8 : 4; }

// Separate colour of rank 3 or 4 (the full-grid svd rank 4 and nmf rank 3 among them): the padded
// rows hold channel c's components from float 4c, so each channel is one group of 4 floats and the
// blend sums the product's groups directly, without the one-hot colour mix (3 loads and 3
// multiply-adds per step). The padded width stays what 3·rank rounds up to: 12 (SSE2) or 16 (AVX2).
bool grouped_channels(const Factors& f) { return f.colour == FactorColour::Separate && (f.rank == 3 || f.rank == 4); }

// The factors as evaluation reads them (FactoredBrdf's padded copies): rows `width` floats apart.
struct FactorView {
    const GridSpec& grid;
    std::size_t width;  // row_width() rounded up to the kernel's lanes, zero-padded
    const float* u;
    const float* v;
    const float* mix;       // 3 × width
    const float* ceiling;   // 3: max_value in the transform space, rounded to float
    bool prefetch_u, prefetch_v;  // prefetch that factor's rows (FactoredBrdf::eval_batch)
    bool grouped;                 // grouped_channels
};

constexpr std::size_t kBlock = 64;  // pairs per pass of the kernel

// The corners of a block's pairs: per corner, the factor rows to blend (row indices) and their
// weights. Stored by corner, not by pair, so the pass that computes them vectorises.
template <int NR, int NC>
struct BlockCorners {
    static constexpr int kRows = NR, kColumns = NC;
    int r[NR][kBlock], c[NC][kBlock];
    float rw[NR][kBlock], cw[NC][kBlock];
};
// h_dp: θh rows; (θd, φd) columns. hd_p: (θh, θd) rows; φd columns.
template <FactorLayout L>
using CornersOf = std::conditional_t<L == FactorLayout::HxDP, BlockCorners<2, 4>, BlockCorners<4, 2>>;

// Pair k's corners from its spans along θh, θd and φd. Branch-free.
template <FactorLayout L>
[[gnu::always_inline]] inline void set_corners(const GridSpec& g, const detail::Corners& s, std::size_t k,
                                               CornersOf<L>& out) {
    const auto hi = [](const detail::Span& a) { return static_cast<float>(a.t); };
    const auto lo = [](const detail::Span& a) { return static_cast<float>(1.0 - a.t); };
    // The 2-D axis: outer span a, inner span b, `inner` samples along b.
    const auto pairs = [&](const detail::Span& a, const detail::Span& b, int inner, int (&idx)[4][kBlock],
                           float (&w)[4][kBlock]) {
        idx[0][k] = a.i0 * inner + b.i0, idx[1][k] = a.i0 * inner + b.i1;
        idx[2][k] = a.i1 * inner + b.i0, idx[3][k] = a.i1 * inner + b.i1;
        w[0][k] = static_cast<float>((1.0 - a.t) * (1.0 - b.t)), w[1][k] = static_cast<float>((1.0 - a.t) * b.t);
        w[2][k] = static_cast<float>(a.t * (1.0 - b.t)), w[3][k] = static_cast<float>(a.t * b.t);
    };
    if constexpr (L == FactorLayout::HxDP) {
        out.r[0][k] = s.h.i0, out.r[1][k] = s.h.i1, out.rw[0][k] = lo(s.h), out.rw[1][k] = hi(s.h);
        pairs(s.d, s.p, g.n_phi_d, out.c, out.cw);
    } else {
        pairs(s.h, s.d, g.n_theta_d, out.r, out.rw);
        out.c[0][k] = s.p.i0, out.c[1][k] = s.p.i1, out.cw[0][k] = lo(s.p), out.cw[1][k] = hi(s.p);
    }
}

// The lane sums of three vectors, in lanes 0-2: pairwise adds of shuffled halves (a horizontal add
// per vector would take three times the shuffles).
[[gnu::always_inline]] inline Float4 lane_sums(const Float4 (&a)[3]) {
    const auto hadd = [](Float4 x, Float4 y) {
        return __builtin_shufflevector(x, y, 0, 2, 4, 6) + __builtin_shufflevector(x, y, 1, 3, 5, 7);
    };
    return hadd(hadd(a[0], a[1]), hadd(a[2], a[2]));
}
[[gnu::always_inline]] inline Float4 lane_sums(const Float8 (&a)[3]) {
    Float4 h[3];
    for (int i = 0; i < 3; ++i)
        h[i] = __builtin_shufflevector(a[i], a[i], 0, 1, 2, 3) + __builtin_shufflevector(a[i], a[i], 4, 5, 6, 7);
    return lane_sums(h);
}

// Pair k's transform-space values y_c = Σ_j mix_cj · (Σ_r rw_r U[r][j]) · (Σ_c cw_c V[c][j]), in
// float, W components at a time. Separate colour's mix is one-hot; multiplying by its zeros costs
// less than the gathers that would avoid it, and rank 3 and 4 (Grouped) skip it. The float sums are within ~1e-7 of the factors'
// magnitude, as the float32 factors themselves.
template <int W, bool Grouped, typename Corners>
[[gnu::always_inline]] inline void blend(const FactorView& f, const Corners& k, std::size_t i, float y[3]) {
    using V = FloatV<W>;
    constexpr int NR = Corners::kRows, NC = Corners::kColumns;
    const float* u[NR];
    const float* v[NC];
    for (int r = 0; r < NR; ++r) u[r] = f.u + static_cast<std::size_t>(k.r[r][i]) * f.width;
    for (int c = 0; c < NC; ++c) v[c] = f.v + static_cast<std::size_t>(k.c[c][i]) * f.width;
    const auto product = [&](std::size_t j) {
        V a = k.rw[0][i] * load<V>(u[0] + j), b = k.cw[0][i] * load<V>(v[0] + j);
        for (int r = 1; r < NR; ++r) a += k.rw[r][i] * load<V>(u[r] + j);
        for (int c = 1; c < NC; ++c) b += k.cw[c][i] * load<V>(v[c] + j);
        return a * b;
    };
    Float4 s;
    if constexpr (Grouped) {
        constexpr std::size_t kSteps = (12 + W - 1) / W;  // the 3 groups, in whole steps
        Float4 g[kSteps * W / 4];
        for (std::size_t step = 0; step < kSteps; ++step) {
            const V p = product(step * W);
            std::memcpy(&g[step * W / 4], &p, sizeof p);
        }
        const Float4 groups[3] = {g[0], g[1], g[2]};
        s = lane_sums(groups);
    } else {
        V acc[3] = {};
        for (std::size_t j = 0; j < f.width; j += W) {
            const V p = product(j);
            for (std::size_t ch = 0; ch < 3; ++ch) acc[ch] += load<V>(f.mix + ch * f.width + j) * p;
        }
        s = lane_sums(acc);
    }
    // At most the data's largest value: bins without data can reconstruct far beyond it (factor.h).
    for (int ch = 0; ch < 3; ++ch) y[ch] = std::min(s[ch], f.ceiling[ch]);
}

// Blocks of pairs in passes, as the tabular kernel: (1) the coordinates, branch-free so the compiler
// vectorises them (the rare pairs whose φd they flag as ill-conditioned recomputed exactly); (2) the
// corners, branch-free and vectorised too, and the prefetches of the factor rows when they miss the
// cache; (3) the blends; (4) the inverse transform, vectorised over the block. W: the blend's floats
// per step.
template <int W, FactorLayout L, bool Grouped>
[[gnu::always_inline]] inline void eval_pairs(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo,
                                              Rgb* out, std::size_t n, std::uint64_t& clamped) {
    const GridSpec& g = f.grid;
    const double off = g.sample_offset();
    detail::BinCoords coords[kBlock];
    CornersOf<L> corners;
    bool above[kBlock];
    float y[3 * kBlock];
    double values[3 * kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        const Vec3* a = wi + start;
        const Vec3* b = wo + start;
        for (std::size_t k = 0; k < m; ++k) coords[k] = detail::fast_bin_coords(g, a[k], b[k]);
        for (std::size_t k = 0; k < m; ++k) above[k] = (a[k].z > 0.0) & (b[k].z > 0.0);
        for (std::size_t k = 0; k < m; ++k)
            if (above[k] & !(coords[k].up <= g.n_phi_d)) [[unlikely]]  // kIllConditioned or NaN
                coords[k] = detail::bin_coords(g, a[k], b[k]);
        for (std::size_t k = 0; k < m; ++k) {
            const detail::BinCoords& c = coords[k];
            set_corners<L>(g,
                           {detail::clamped_span(c.uh - off, g.n_theta_h), detail::clamped_span(c.ud - off, g.n_theta_d),
                            detail::periodic_span(c.up - off, g.n_phi_d)},
                           k, corners);
        }
        if (f.prefetch_u)
            for (std::size_t k = 0; k < m; ++k)
                for (const auto& r : corners.r) __builtin_prefetch(f.u + static_cast<std::size_t>(r[k]) * f.width);
        if (f.prefetch_v)
            for (std::size_t k = 0; k < m; ++k)
                for (const auto& c : corners.c) __builtin_prefetch(f.v + static_cast<std::size_t>(c[k]) * f.width);
        for (std::size_t k = 0; k < m; ++k) {
            if (above[k])
                blend<W, Grouped>(f, corners, k, y + 3 * k);
            else
                y[3 * k] = y[3 * k + 1] = y[3 * k + 2] = 0.0f;  // gives the value 0, not counted
        }
        from_space_n(space, y, values, 3 * m, clamped);
        for (std::size_t k = 0; k < m; ++k) out[start + k] = {values[3 * k], values[3 * k + 1], values[3 * k + 2]};
    }
}

// The kernel's two builds. Single-pair eval runs the same one as the batch (bit for bit: FMA
// contraction makes the two builds' results differ in the last bits).
template <FactorLayout L, bool Grouped>
[[gnu::flatten]] void eval_pairs_sse2(const FactorView& f, FactorSpace space, const Vec3* wi, const Vec3* wo,
                                      Rgb* out, std::size_t n, std::uint64_t& clamped) {
    eval_pairs<4, L, Grouped>(f, space, wi, wo, out, n, clamped);
}

template <FactorLayout L, bool Grouped>
[[gnu::flatten, gnu::target("avx2,fma")]] void eval_pairs_avx2(const FactorView& f, FactorSpace space, const Vec3* wi,
                                                                const Vec3* wo, Rgb* out, std::size_t n,
                                                                std::uint64_t& clamped) {
    eval_pairs<8, L, Grouped>(f, space, wi, wo, out, n, clamped);
}

template <bool Grouped>
void eval_kernel(detail::Simd simd, FactorLayout layout, const FactorView& f, FactorSpace space, const Vec3* wi,
                 const Vec3* wo, Rgb* out, std::size_t n, std::uint64_t& clamped) {
    constexpr FactorLayout kHxDP = FactorLayout::HxDP, kHDxP = FactorLayout::HDxP;
    const bool hxdp = layout == kHxDP;
    if (simd == detail::Simd::Avx2Fma)
        (hxdp ? eval_pairs_avx2<kHxDP, Grouped> : eval_pairs_avx2<kHDxP, Grouped>)(f, space, wi, wo, out, n, clamped);
    else
        (hxdp ? eval_pairs_sse2<kHxDP, Grouped> : eval_pairs_sse2<kHDxP, Grouped>)(f, space, wi, wo, out, n, clamped);
}

// ---------------------------------------------------------------------------------------------
// Factorisation: alternating weighted least squares

using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Vec = Eigen::VectorXd;

// min ½ uᵀAu − bᵀu subject to u ≥ 0, by coordinate descent from the given u (A positive definite).
void nnls(const Eigen::MatrixXd& a, const Vec& b, Vec& u) {
    const Eigen::Index k = u.size();
    for (int sweep = 0; sweep < 20; ++sweep) {  // warm-started: a few sweeps per outer iteration suffice
        double change = 0.0, scale = 0.0;
        for (Eigen::Index i = 0; i < k; ++i) {
            const double next = std::max(0.0, u[i] + (b[i] - a.row(i).dot(u)) / a(i, i));
            change = std::max(change, std::fabs(next - u[i]));
            u[i] = next;
            scale = std::max(scale, next);
        }
        if (change <= 1e-9 * scale) break;
    }
}

// What one side of an alternating step needs, row i of each matrix being row i of that side's factor
// (the other side sees the transposes). Row-major, so a row is contiguous.
struct Side {
    Mat w;                // weights: 0 for invalid bins
    std::vector<Mat> wx;  // per channel: w ∘ y
    Vec xx;               // per row: Σ_c Σ_j w y², for the objective
};

// Normal equations of the colour weights s, accumulated while updating V (shared colour only).
struct ColourSums {
    Eigen::MatrixXd k;   // Σ_j (v_j v_jᵀ) ∘ G_j
    std::vector<Vec> r;  // per channel: Σ_j v_j ∘ (Uᵀ (w_j ∘ y_cj))
    double objective = 0.0;
};

constexpr int kChunks = 32;  // fixed work split, so results do not depend on the thread count
// Small enough that a masked table factored at full rank is still reproduced (5e-7 relative; 1e-3
// gave 4e-5), large enough to bound the extrapolation (a 16×16×32 coat, rank 4, log space: 625 -> 7).
constexpr double kRidge = 1e-5;

// Updates every row of `out` given the other factor F: row i minimises
//   Σ_c Σ_j w_ij (y_cij − Σ_a out_ia s_ca F_ja)² + Σ_a λ_ia out_ia²
// (non-negatively for nmf). In log and cbrt space the ridge λ_ia is `ridge` times what row i's
// diagonal of the normal equations lacks of the mean over rows (0 for a row as well measured as the
// average, so a fully valid table is factored exactly): a row with few valid bins, or nearly
// collinear ones, has its undetermined directions pulled towards 0 instead of fitting its few values
// with large opposite components, which extrapolate into the invalid bins and there, through expm1
// or the cube, far beyond the data (RGL cc_ibiza_sunset at grazing θd, nmf rank 2, log space: values
// past e^700). In linear and cos space the extrapolation stays linear, eval's ceiling bounds it, and
// the ridge would cost accuracy (svd rank 4 on a GGX plastic: cos_rmse_rel 0.0003 -> 0.01), so
// `ridge` is 0 there. Rows without any valid bin come out 0. A ridge of 1e-10 of the row's own
// diagonal keeps the equations definite. Its normal equations are G_i ∘ (Σ_c s_c s_cᵀ)
// with G_i = Σ_j w_ij F_j F_jᵀ: for all rows at once, one product W·P with P_j = vec(F_j F_jᵀ), and
// the right-hand sides (W ∘ Y_c)·F. Returns the objective after the update and the colour weights'
// normal equations.
ColourSums update_side(Mat& out, const Mat& other, const Side& side, const Mat& s, bool nonneg, double ridge,
                       int threads) {
    const Eigen::Index n = out.rows(), k = out.cols(), m = other.rows();
    const int channels = static_cast<int>(side.wx.size());
    Eigen::MatrixXd s2 = Eigen::MatrixXd::Zero(k, k);
    for (int c = 0; c < channels; ++c) s2 += s.row(c).transpose() * s.row(c);
    Mat outer(m, k * k);
    for (Eigen::Index j = 0; j < m; ++j)
        for (Eigen::Index a = 0; a < k; ++a)
            for (Eigen::Index b = 0; b < k; ++b) outer(j, a * k + b) = other(j, a) * other(j, b);
    // Mean over rows of diag(G_i ∘ s2): Σ_j (Σ_i w_ij) F_ja² · s2_aa / n.
    const Vec mean_diagonal = (other.cwiseAbs2().transpose() * side.w.colwise().sum().transpose())
                                  .cwiseProduct(s2.diagonal()) / static_cast<double>(n);

    const int chunks = static_cast<int>(std::min<Eigen::Index>(n, kChunks));
    std::vector<ColourSums> sums(chunks);
    detail::parallel_for(chunks, threads, [&](int, int chunk) {
        const Eigen::Index begin = n * chunk / chunks, len = n * (chunk + 1) / chunks - begin;
        const Mat grams = side.w.middleRows(begin, len) * outer;
        std::vector<Mat> rhs(channels);
        for (int c = 0; c < channels; ++c) rhs[c] = side.wx[c].middleRows(begin, len) * other;
        ColourSums& acc = sums[chunk];
        acc.k = Eigen::MatrixXd::Zero(k, k);
        acc.r.assign(channels, Vec::Zero(k));
        Eigen::MatrixXd g(k, k), a(k, k), ridged(k, k);
        Vec b(k), u(k);
        Eigen::LDLT<Eigen::MatrixXd> ldlt(k);
        for (Eigen::Index r = 0; r < len; ++r) {
            g = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                grams.row(r).data(), k, k);
            b.setZero();
            for (int c = 0; c < channels; ++c) b += s.row(c).transpose().cwiseProduct(rhs[c].row(r).transpose());
            a = g.cwiseProduct(s2);
            ridged = a;
            ridged.diagonal() += ridge * (mean_diagonal - a.diagonal()).cwiseMax(0.0);
            ridged.diagonal().array() += 1e-10 * a.trace() / static_cast<double>(k) + 1e-300;
            u = out.row(begin + r).transpose();
            if (nonneg) {
                nnls(ridged, b, u);
            } else {
                ldlt.compute(ridged);
                u = ldlt.solve(b);
            }
            out.row(begin + r) = u.transpose();
            acc.objective += std::max(0.0, side.xx[begin + r] - 2.0 * u.dot(b) + u.dot(a * u));
            acc.k += (u * u.transpose()).cwiseProduct(g);
            for (int c = 0; c < channels; ++c) acc.r[c] += u.cwiseProduct(rhs[c].row(r).transpose());
        }
    });
    ColourSums total{Eigen::MatrixXd::Zero(k, k), std::vector<Vec>(channels, Vec::Zero(k)), 0.0};
    for (const ColourSums& a : sums) {
        total.k += a.k;
        for (int c = 0; c < channels; ++c) total.r[c] += a.r[c];
        total.objective += a.objective;
    }
    return total;
}

// A table's valid bins in one layout and transform space: the values y (rows × columns, 0 where
// invalid) and the two Sides.
struct Data {
    std::vector<Mat> y;
    Side rows, cols;
    std::size_t valid = 0;
};

struct Solved {
    Mat u, v, s;  // rows × k, columns × k, channels × k
    int iterations = 0;
    bool converged = false;
    double objective = 0.0, norm = 0.0;  // Σ w (y − ŷ)², Σ w y²
};

// Each component's scale (`scale` of its U and of its V column) moved between U, V and s; the product
// is unchanged. With colour weights the scales go into s; without, U and V columns get equal scales.
template <typename Scale>
void move_column_scales(Solved& r, bool shared, Scale scale) {
    for (Eigen::Index j = 0; j < r.u.cols(); ++j) {
        const double su = scale(r.u.col(j)), sv = scale(r.v.col(j));
        if (!(su > 0.0 && sv > 0.0)) continue;
        if (shared) {
            r.u.col(j) /= su;
            r.v.col(j) /= sv;
            r.s.col(j) *= su * sv;
        } else {
            const double g = std::sqrt(su * sv);
            r.u.col(j) *= g / su;
            r.v.col(j) *= g / sv;
        }
    }
}

// Column norms balanced so that no factor's scale drifts.
void balance(Solved& r, bool shared) {
    move_column_scales(r, shared, [](const auto& c) { return c.norm(); });
}

// Rewrites U·Vᵀ as its SVD (U' = Q_u A √Σ, V' = Q_v B √Σ): orthogonal columns, so float32 storage
// of the factors loses no more than float32 storage of the table would.
void canonical_svd(Solved& r) {
    const Eigen::Index k = r.u.cols();
    const Eigen::HouseholderQR<Eigen::MatrixXd> qu(r.u), qv(r.v);
    const Eigen::MatrixXd ru = qu.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd rv = qv.matrixQR().topRows(k).triangularView<Eigen::Upper>();
    const Eigen::JacobiSVD<Eigen::MatrixXd> core(ru * rv.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd root = core.singularValues().cwiseSqrt();
    r.u = qu.householderQ() * Eigen::MatrixXd::Identity(r.u.rows(), k) * core.matrixU() * root.asDiagonal();
    r.v = qv.householderQ() * Eigen::MatrixXd::Identity(r.v.rows(), k) * core.matrixV() * root.asDiagonal();
}

// NNDSVD (Boutsidis & Gallopoulos 2008): each SVD component u vᵀ replaced by the larger (by norm
// product) of its positive part u₊v₊ᵀ and negated negative part u₋v₋ᵀ, a non-negative start close to
// the truncated SVD. The leading component of a non-negative matrix is one-signed already.
void nndsvd(Mat& u, Mat& v) {
    for (Eigen::Index j = 0; j < u.cols(); ++j) {
        const Vec up = u.col(j).cwiseMax(0.0), un = (-u.col(j)).cwiseMax(0.0);
        const Vec vp = v.col(j).cwiseMax(0.0), vn = (-v.col(j)).cwiseMax(0.0);
        const double mp = up.norm() * vp.norm(), mn = un.norm() * vn.norm();
        // u.col(j) and v.col(j) carry √σ each: keep the product's scale, σ·m/(|u|·|v|).
        const double scale = std::sqrt(u.col(j).norm() * v.col(j).norm());
        const bool pos = mp >= mn;
        const Vec& a = pos ? up : un;
        const Vec& b = pos ? vp : vn;
        const double m = pos ? mp : mn;
        if (!(m > 0.0)) {
            u.col(j).setZero();
            v.col(j).setZero();
            continue;
        }
        const double g = scale * std::sqrt(m / (u.col(j).norm() * v.col(j).norm()));
        u.col(j) = g * a / a.norm();
        v.col(j) = g * b / b.norm();
    }
}

// One factorisation of `channels` matrices sharing U and V (colour weights s updated when there is
// more than one channel). `step(i)` reports progress after iteration i.
Solved solve(const Data& d, int k, bool nonneg, const FactorOptions& o, const std::function<void(int)>& step) {
    const Side &rows = d.rows, &cols = d.cols;
    const int channels = static_cast<int>(d.y.size());
    const Eigen::Index nr = rows.w.rows(), nc = cols.w.rows();
    Solved r;
    r.norm = rows.xx.sum();

    // Start: the rank-k SVD of the channels' mean, invalid entries filled with their row's weighted
    // mean (zeros would pull every component towards them); nmf starts from its NNDSVD.
    Mat mean = Mat::Zero(nr, nc);
    for (int c = 0; c < channels; ++c) mean += d.y[c] / channels;
    for (Eigen::Index i = 0; i < nr; ++i) {
        const double wsum = rows.w.row(i).sum();
        const double fill = wsum > 0.0 ? mean.row(i).dot(rows.w.row(i)) / wsum : 0.0;
        for (Eigen::Index j = 0; j < nc; ++j)
            if (!(rows.w(i, j) > 0.0)) mean(i, j) = fill;
    }
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(mean, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Vec root = svd.singularValues().head(k).cwiseSqrt();
    r.u = svd.matrixU().leftCols(k) * root.asDiagonal();
    r.v = svd.matrixV().leftCols(k) * root.asDiagonal();
    if (nonneg) nndsvd(r.u, r.v);
    r.s = Mat::Ones(channels, k);
    if (channels > 1) {  // each channel's share of the mean
        const double base = mean.cwiseProduct(rows.w).sum();
        for (int c = 0; c < channels; ++c) {
            const double ratio = base > 0.0 ? rows.wx[c].sum() / base : 1.0;
            r.s.row(c).setConstant(ratio > 0.0 ? ratio : 1.0);
        }
    }

    const double ridge = o.space == FactorSpace::Log || o.space == FactorSpace::Cbrt ? kRidge : 0.0;
    double previous = 0.0;
    for (int it = 1; it <= o.max_iterations; ++it) {
        update_side(r.u, r.v, rows, r.s, nonneg, ridge, o.threads);
        const ColourSums sums = update_side(r.v, r.u, cols, r.s, nonneg, ridge, o.threads);
        r.objective = sums.objective;
        r.iterations = it;
        if (channels > 1) {
            Eigen::MatrixXd kk = sums.k;
            kk.diagonal().array() += 1e-10 * sums.k.trace() / k + 1e-300;
            for (int c = 0; c < channels; ++c) {
                Vec s = r.s.row(c).transpose();
                if (nonneg)
                    nnls(kk, sums.r[c], s);
                else
                    s = kk.ldlt().solve(sums.r[c]);
                r.s.row(c) = s.transpose();
            }
        }
        balance(r, channels > 1);
        if (!std::isfinite(r.objective) || !r.u.allFinite() || !r.v.allFinite() || !r.s.allFinite())
            throw ValueError(std::string(factor_method_name(o.method)) +
                             ": the factorisation diverged (non-finite values after " + std::to_string(it) +
                             " iterations)");
        step(it);
        if (r.objective <= 1e-24 * r.norm || (it > 1 && previous - r.objective <= o.tolerance * previous)) {
            r.converged = true;
            break;
        }
        previous = r.objective;
    }
    if (!nonneg && channels == 1) canonical_svd(r);
    return r;
}

// The largest value of each channel over the bins prepare() takes (all channels finite and ≥ 0).
std::array<float, 3> data_max(const Table& table) {
    std::array<float, 3> top{0.0f, 0.0f, 0.0f};
    for (std::size_t bin = 0; bin < table.bins(); ++bin) {
        const float f[3] = {table.at(bin, 0), table.at(bin, 1), table.at(bin, 2)};
        if (!(std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2]) && f[0] >= 0 && f[1] >= 0 && f[2] >= 0))
            continue;
        for (int c = 0; c < 3; ++c) top[c] = std::max(top[c], f[c]);
    }
    return top;
}

Data prepare(const Table& table, const FactorOptions& o, int rows, int cols, const std::vector<int>& channels) {
    const GridSpec& g = table.grid();
    const int nch = static_cast<int>(channels.size());
    Data d;
    Mat w = Mat::Zero(rows, cols);
    d.y.assign(nch, Mat::Zero(rows, cols));
    for (std::size_t bin = 0; bin < table.bins(); ++bin) {
        bool ok = true;
        for (int c = 0; c < 3; ++c) {
            const float f = table.at(bin, c);
            ok = ok && std::isfinite(f) && f >= 0.0f;
        }
        if (!ok) continue;
        double weight = 1.0;
        if (o.space == FactorSpace::Cos) {
            const int ip = static_cast<int>(bin % g.n_phi_d), id = static_cast<int>(bin / g.n_phi_d % g.n_theta_d),
                      ih = static_cast<int>(bin / g.n_phi_d / g.n_theta_d);
            const double cos_i = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)}).first.z;
            weight = cos_i > 0.0 ? cos_i * cos_i : 0.0;
            // On a warped θd axis, each sample stands for dθd/du of the metric's linear θd axis.
            if (g.theta_d_warp != 0.0)
                weight *= 1.0 / (1.0 - g.theta_d_warp + g.theta_d_warp * std::numbers::pi / 2.0 * std::sin(g.theta_d_at(id)));
        }
        if (!(weight > 0.0)) continue;
        ++d.valid;
        const Eigen::Index i = static_cast<Eigen::Index>(bin / cols), j = static_cast<Eigen::Index>(bin % cols);
        w(i, j) = weight;
        for (int c = 0; c < nch; ++c) d.y[c](i, j) = to_space(o.space, table.at(bin, channels[c]));
    }
    d.rows.xx = Vec::Zero(rows);
    d.cols.xx = Vec::Zero(cols);
    for (int c = 0; c < nch; ++c) {
        const Mat wx = w.cwiseProduct(d.y[c]);
        const Mat wxx = wx.cwiseProduct(d.y[c]);
        d.rows.xx += wxx.rowwise().sum();
        d.cols.xx += wxx.colwise().sum().transpose();
        d.rows.wx.push_back(wx);
        d.cols.wx.push_back(wx.transpose());
    }
    d.cols.w = w.transpose();
    d.rows.w = std::move(w);
    return d;
}

// ---------------------------------------------------------------------------------------------
// Fit through the lookup (fit=lsq)

// What the refit sees of each point: its values in the transform space and its weight (the squared row
// scale of detail::fit_points, times cos²θi in cos space).
struct LookupPoints {
    std::vector<std::array<double, 3>> y;
    std::vector<double> w;
};

// One factor as the points read it: per point, the `corners` rows eval's blend reads and their weights,
// and the block pattern of that factor's normal equations (the row pairs any point couples, sorted),
// with each point's corner pairs as indices into it.
struct LookupSide {
    int rows = 0, corners = 0;
    std::vector<int> row;                            // points × corners
    std::vector<double> weight;                      // points × corners
    std::vector<std::pair<int, int>> blocks;         // (q, q'), both orders
    std::vector<int> slot;                           // points × corners²

    // The interpolated factor row at point p: Σ_r weight_r · f.row(row_r).
    template <typename Out>
    void blend(const Mat& f, std::size_t p, Out& out) const {
        out = weight[p * corners] * f.row(row[p * corners]);
        for (int r = 1; r < corners; ++r) out += weight[p * corners + r] * f.row(row[p * corners + r]);
    }
};

// The refit's chunks of points: a fixed split, so results do not depend on the thread count; few,
// because each holds a copy of the normal equations' blocks.
constexpr int kFitChunks = 4;
// Bounds on one factor's normal equations (doubles in the blocks: 32 MiB per chunk) and unknowns.
constexpr std::size_t kMaxFitEntries = std::size_t{1} << 22, kMaxFitUnknowns = std::size_t{1} << 18;

// Refuses (before any work) a refit whose points or normal equations exceed the bounds: a factor row
// couples with at most 3 rows along a 1-D axis of the grid and 9 on a 2-D one.
void check_fit_size(const Factors& f, int supersample, const char* method) {
    const std::size_t ss = static_cast<std::size_t>(supersample);
    const std::size_t points = f.grid.bins() * ss * ss * ss;
    if (points > detail::kMaxFitPoints)
        throw ValueError(std::string(method) + " fit=lsq: least squares over " + std::to_string(points) +
                         " points (more than 2^21); lower ss= or the resolution");
    const std::size_t m = static_cast<std::size_t>(f.row_width());
    const bool hxdp = f.layout == FactorLayout::HxDP;
    const std::size_t sides[2][2] = {{static_cast<std::size_t>(f.rows()), hxdp ? 3u : 9u},
                                     {static_cast<std::size_t>(f.columns()), hxdp ? 9u : 3u}};
    for (const auto& [rows, neighbours] : sides)
        if (rows * m > kMaxFitUnknowns || rows * neighbours * m * m > kMaxFitEntries)
            throw ValueError(std::string(method) + " fit=lsq: a factor's normal equations would have " +
                             std::to_string(rows * m) + " unknowns and up to " + std::to_string(rows * neighbours * m * m) +
                             " entries (at most 2^18 and 2^22); lower the rank or the resolution");
}

LookupSide lookup_side(int rows, int corners, std::vector<int> row, std::vector<double> weight) {
    LookupSide s;
    s.rows = rows;
    s.corners = corners;
    s.row = std::move(row);
    s.weight = std::move(weight);
    const std::size_t points = s.row.size() / static_cast<std::size_t>(corners);
    std::vector<std::int64_t> keys;
    keys.reserve(points * corners * corners);
    for (std::size_t p = 0; p < points; ++p)
        for (int a = 0; a < corners; ++a)
            for (int b = 0; b < corners; ++b)
                keys.push_back(std::int64_t{s.row[p * corners + a]} * rows + s.row[p * corners + b]);
    std::vector<std::int64_t> unique = keys;
    std::sort(unique.begin(), unique.end());
    unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
    for (std::int64_t k : unique) s.blocks.emplace_back(static_cast<int>(k / rows), static_cast<int>(k % rows));
    s.slot.resize(keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i)
        s.slot[i] = static_cast<int>(std::lower_bound(unique.begin(), unique.end(), keys[i]) - unique.begin());
    return s;
}

// min ½ xᵀAx − bᵀx subject to x ≥ 0 by projected Gauss-Seidel from the given x (A symmetric positive
// definite, both triangles stored): nmf's step on the sparse normal equations, warm-started.
void nnls(const Eigen::SparseMatrix<double>& a, const Vec& b, Vec& x) {
    const Vec diagonal = a.diagonal();
    for (int sweep = 0; sweep < 200; ++sweep) {
        double change = 0.0, scale = 0.0;
        for (Eigen::Index i = 0; i < a.outerSize(); ++i) {
            double ax = 0.0;
            for (Eigen::SparseMatrix<double>::InnerIterator it(a, i); it; ++it) ax += it.value() * x[it.index()];
            const double next = std::max(0.0, x[i] + (b[i] - ax) / diagonal[i]);
            change = std::max(change, std::fabs(next - x[i]));
            x[i] = next;
            scale = std::max(scale, next);
        }
        if (change <= 1e-9 * scale) break;
    }
}

// Updates every row of x (side xs) given the other factor y (side ys) and the mix (3 × m: colour
// weights, or separate colour's one-hot selection): minimises
//   Σ_p w_p Σ_c (y_pc − Σ_j mix_cj x̃_pj ỹ_pj)² + λ |x − x_prev|²
// where x̃, ỹ blend the rows eval reads. Point p's rows of x enter with the design vectors
// a_r · (mix_c ∘ ỹ_p), so its normal-equation block for rows (q, q') is a_q a_q' w_p diag(ỹ) MᵀM diag(ỹ).
// λ = 1e-6 of the mean diagonal: keeps the system definite and leaves rows no point reaches where
// they were. nmf: x ≥ 0 (projected Gauss-Seidel).
void lookup_step(Mat& x, const LookupSide& xs, const Mat& y, const LookupSide& ys, const Mat& mix,
                 const LookupPoints& pts, bool nonneg, int threads, const char* method) {
    const Eigen::Index m = x.cols();
    const std::size_t points = pts.w.size(), nblocks = xs.blocks.size();
    const Eigen::MatrixXd s2 = mix.transpose() * mix;
    struct Acc {
        std::vector<double> blocks;  // nblocks × m × m
        Mat rhs;                     // rows × m
    };
    std::vector<Acc> acc(kFitChunks);
    detail::parallel_for(kFitChunks, threads, [&](int, int chunk) {
        Acc& a = acc[chunk];
        a.blocks.assign(nblocks * m * m, 0.0);
        a.rhs = Mat::Zero(xs.rows, m);
        Eigen::RowVectorXd other(m), z(m), r(m);
        Eigen::MatrixXd g(m, m);
        const std::size_t begin = points * chunk / kFitChunks, end = points * (chunk + 1) / kFitChunks;
        for (std::size_t p = begin; p < end; ++p) {
            ys.blend(y, p, other);
            const Eigen::Vector3d yp(pts.y[p][0], pts.y[p][1], pts.y[p][2]);
            z = yp.transpose() * mix;  // Σ_c y_c mix_c
            r = pts.w[p] * other.cwiseProduct(z);
            g = pts.w[p] * (other.transpose() * other).cwiseProduct(s2);
            const int nc = xs.corners;
            for (int i = 0; i < nc; ++i) {
                const double wi = xs.weight[p * nc + i];
                a.rhs.row(xs.row[p * nc + i]) += wi * r;
                for (int k = 0; k < nc; ++k) {
                    const double wik = wi * xs.weight[p * nc + k];
                    if (wik == 0.0) continue;
                    Eigen::Map<Eigen::MatrixXd>(a.blocks.data() + xs.slot[(p * nc + i) * nc + k] * m * m, m, m) += wik * g;
                }
            }
        }
    });
    for (int c = 1; c < kFitChunks; ++c) {
        for (std::size_t i = 0; i < acc[0].blocks.size(); ++i) acc[0].blocks[i] += acc[c].blocks[i];
        acc[0].rhs += acc[c].rhs;
    }
    const Eigen::Index n = static_cast<Eigen::Index>(xs.rows) * m;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(nblocks * m * m + n);
    double trace = 0.0;
    for (std::size_t b = 0; b < nblocks; ++b) {
        const auto [q, q2] = xs.blocks[b];
        const double* block = acc[0].blocks.data() + b * m * m;  // column-major m × m
        for (Eigen::Index j = 0; j < m; ++j)
            for (Eigen::Index i = 0; i < m; ++i) {
                entries.emplace_back(q * m + i, q2 * m + j, block[j * m + i]);
                if (q == q2 && i == j) trace += block[j * m + i];
            }
    }
    const double lambda = 1e-6 * trace / static_cast<double>(n) + 1e-300;
    for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, lambda);
    Eigen::SparseMatrix<double> normal(n, n);
    normal.setFromTriplets(entries.begin(), entries.end());
    Vec previous = Eigen::Map<const Vec>(x.data(), n);  // row-major: row q's m entries together
    const Vec rhs = Eigen::Map<const Vec>(acc[0].rhs.data(), n) + lambda * previous;
    if (nonneg) {
        nnls(normal, rhs, previous);
        Eigen::Map<Vec>(x.data(), n) = previous;
        return;
    }
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
    if (ldlt.info() != Eigen::Success) throw ValueError(std::string(method) + " fit=lsq: the normal equations are singular");
    Eigen::Map<Vec>(x.data(), n) = ldlt.solve(rhs);
}

// The colour weights' normal equations over the points, K = Σ w (ũ∘ṽ)(ũ∘ṽ)ᵀ and r_c = Σ w y_c (ũ∘ṽ),
// and Σ w y_c²: enough for the weights' update and the objective Σ_c (yy_c − 2 s_cᵀ r_c + s_cᵀ K s_c).
struct MixSums {
    Eigen::MatrixXd k;
    Eigen::MatrixXd r;  // m × 3
    double yy = 0.0;
    double objective(const Mat& mix) const {
        double sum = yy;
        for (int c = 0; c < 3; ++c) {
            const Vec s = mix.row(c).transpose();
            sum += s.dot(k * s) - 2.0 * s.dot(r.col(c));
        }
        return std::max(0.0, sum);
    }
};

MixSums mix_sums(const Mat& u, const LookupSide& us, const Mat& v, const LookupSide& vs, const LookupPoints& pts,
                 int threads) {
    const Eigen::Index m = u.cols();
    const std::size_t points = pts.w.size();
    std::vector<MixSums> acc(kFitChunks);
    detail::parallel_for(kFitChunks, threads, [&](int, int chunk) {
        MixSums& a = acc[chunk];
        a.k = Eigen::MatrixXd::Zero(m, m);
        a.r = Eigen::MatrixXd::Zero(m, 3);
        Eigen::RowVectorXd uu(m), vv(m);
        Vec q(m);
        for (std::size_t p = points * chunk / kFitChunks; p < points * (chunk + 1) / kFitChunks; ++p) {
            us.blend(u, p, uu);
            vs.blend(v, p, vv);
            q = uu.cwiseProduct(vv).transpose();
            a.k.selfadjointView<Eigen::Lower>().rankUpdate(q, pts.w[p]);
            for (int c = 0; c < 3; ++c) {
                a.r.col(c) += pts.w[p] * pts.y[p][c] * q;
                a.yy += pts.w[p] * pts.y[p][c] * pts.y[p][c];
            }
        }
    });
    MixSums total = std::move(acc[0]);
    for (int c = 1; c < kFitChunks; ++c) {
        total.k += acc[c].k;
        total.r += acc[c].r;
        total.yy += acc[c].yy;
    }
    const Eigen::MatrixXd full = total.k.selfadjointView<Eigen::Lower>();
    total.k = full;
    return total;
}

// Shared colour: the weights s_c minimising the objective given U and V (≥ 0 for nmf).
void update_mix(Mat& mix, const MixSums& sums, bool nonneg) {
    Eigen::MatrixXd kk = sums.k;
    kk.diagonal().array() += 1e-10 * sums.k.trace() / static_cast<double>(kk.rows()) + 1e-300;
    for (int c = 0; c < 3; ++c) {
        Vec s = mix.row(c).transpose();
        if (nonneg)
            nnls(kk, Vec(sums.r.col(c)), s);
        else
            s = kk.ldlt().solve(sums.r.col(c));
        mix.row(c) = s.transpose();
    }
}

// float16 storage: each component's U and V columns scaled to a largest magnitude of 1, the scale
// moved into the (float32) colour weights; for separate colour both to the geometric mean of their
// largest magnitudes. Either way far from float16's range limits, where its relative precision holds.
void scale_for_f16(Solved& r, bool shared) {
    move_column_scales(r, shared, [](const auto& c) { return c.cwiseAbs().maxCoeff(); });
}

double to_f16(double x) { return static_cast<float>(Eigen::half(static_cast<float>(x))); }

// fit=lsq's outside points (tabulate.h): a tenth of the row scale, as filter=lsq weighs them.
constexpr double kOutsideScale = 0.1;

// The refit of fit=lsq (factored.h), from the sample fit's factors `start`. r.s holds the mix.
void refit(const Brdf& source, const Factors& start, const FactorOptions& o, Solved& r, FactorReport& report,
           std::array<float, 3>& top) {
    const char* method = factor_method_name(o.method);
    const GridSpec& g = start.grid;
    const bool nonneg = o.method == FactorMethod::Nmf, shared = o.colour == FactorColour::Shared;
    const int m = start.row_width(), k = start.rank, rows = start.rows(), cols = start.columns();
    using FloatRows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    r.u = Eigen::Map<const FloatRows>(start.u.data(), rows, m).cast<double>();
    r.v = Eigen::Map<const FloatRows>(start.v.data(), cols, m).cast<double>();
    r.s = Mat::Zero(3, m);
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < k; ++j)
            if (shared)
                r.s(c, j) = start.colour_weights[static_cast<std::size_t>(c) * k + j];
            else
                r.s(c, c * k + j) = 1.0;

    TabulateOptions tab;
    tab.grid = g;
    tab.supersample = {o.supersample, o.supersample, o.supersample};
    tab.threads = o.threads;
    const detail::FitPoints fp = detail::fit_points(source, tab, kOutsideScale);
    const std::size_t points = fp.wi.size();
    if (points == 0) throw ValueError(std::string(method) + " fit=lsq: no valid points to fit");
    LookupPoints pts;
    pts.y.resize(points);
    pts.w.resize(points);
    const bool hxdp = o.layout == FactorLayout::HxDP;
    const int uc = hxdp ? 2 : 4, vc = hxdp ? 4 : 2;
    std::vector<int> urow(points * uc), vrow(points * vc);
    std::vector<double> uw(points * uc), vw(points * vc);
    for (std::size_t p = 0; p < points; ++p) {
        const Vec3 &wi = fp.wi[p], &wo = fp.wo[p];
        const double cos_i = o.space == FactorSpace::Cos ? wi.z : 1.0;
        pts.w[p] = fp.scale[p] * fp.scale[p] * cos_i * cos_i;
        for (int c = 0; c < 3; ++c) {
            pts.y[p][c] = to_space(o.space, fp.value[p][c]);
            top[c] = std::max(top[c], static_cast<float>(fp.value[p][c]));
        }
        // Eval's corners (set_corners): the 1-D axis's two rows, the 2-D axis's four (outer a, inner b).
        const detail::Corners s = detail::linear_corners(g, detail::fast_bin_coords(g, wi, wo), wi, wo);
        const auto one = [&](const detail::Span& a, int* row, double* w) {
            row[0] = a.i0, row[1] = a.i1, w[0] = 1.0 - a.t, w[1] = a.t;
        };
        const auto two = [&](const detail::Span& a, const detail::Span& b, int inner, int* row, double* w) {
            row[0] = a.i0 * inner + b.i0, row[1] = a.i0 * inner + b.i1;
            row[2] = a.i1 * inner + b.i0, row[3] = a.i1 * inner + b.i1;
            w[0] = (1.0 - a.t) * (1.0 - b.t), w[1] = (1.0 - a.t) * b.t, w[2] = a.t * (1.0 - b.t), w[3] = a.t * b.t;
        };
        if (hxdp) {
            one(s.h, &urow[p * uc], &uw[p * uc]);
            two(s.d, s.p, g.n_phi_d, &vrow[p * vc], &vw[p * vc]);
        } else {
            two(s.h, s.d, g.n_theta_d, &urow[p * uc], &uw[p * uc]);
            one(s.p, &vrow[p * vc], &vw[p * vc]);
        }
    }
    const LookupSide us = lookup_side(rows, uc, std::move(urow), std::move(uw));
    const LookupSide vs = lookup_side(cols, vc, std::move(vrow), std::move(vw));
    report.fit_points = points;

    MixSums sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
    const double norm = sums.yy;
    double objective = sums.objective(r.s);
    report.fit_residual_start = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
    for (int it = 1; it <= o.fit_iterations; ++it) {
        lookup_step(r.u, us, r.v, vs, r.s, pts, nonneg, o.threads, method);
        lookup_step(r.v, vs, r.u, us, r.s, pts, nonneg, o.threads, method);
        sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
        if (shared) update_mix(r.s, sums, nonneg);
        const double previous = objective;
        objective = sums.objective(r.s);
        balance(r, shared);
        report.fit_iterations = it;
        if (!std::isfinite(objective) || !r.u.allFinite() || !r.v.allFinite() || !r.s.allFinite())
            throw ValueError(std::string(method) + " fit=lsq: the refit diverged (non-finite values after " +
                             std::to_string(it) + " iterations)");
        if (o.progress) o.progress(0.25 + 0.75 * it / o.fit_iterations);
        if (previous - objective <= o.tolerance * previous) break;
    }
    if (o.dtype == FactorDtype::F16) {
        // Round U, refit V to the rounded U, round V, refit the (float32) colour weights.
        scale_for_f16(r, shared);
        r.u = r.u.unaryExpr([](double x) { return to_f16(x); });
        lookup_step(r.v, vs, r.u, us, r.s, pts, nonneg, o.threads, method);
        r.v = r.v.unaryExpr([](double x) { return to_f16(x); });
        sums = mix_sums(r.u, us, r.v, vs, pts, o.threads);
        if (shared) update_mix(r.s, sums, nonneg);
        objective = sums.objective(r.s);
    }
    report.fit_residual = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* factor_method_name(FactorMethod m) { return name_of(kMethods, m); }
const char* factor_space_name(FactorSpace s) { return name_of(kSpaces, s); }
const char* factor_layout_name(FactorLayout l) { return name_of(kLayouts, l); }
const char* factor_colour_name(FactorColour c) { return name_of(kColours, c); }
FactorMethod parse_factor_method(const std::string& name) { return parse(kMethods, name, "method"); }
FactorSpace parse_factor_space(const std::string& name) { return parse(kSpaces, name, "space"); }
FactorLayout parse_factor_layout(const std::string& name) { return parse(kLayouts, name, "layout"); }
FactorColour parse_factor_colour(const std::string& name) { return parse(kColours, name, "colour"); }
const char* factor_fit_name(FactorFit f) { return name_of(kFits, f); }
const char* factor_dtype_name(FactorDtype d) { return name_of(kDtypes, d); }
FactorFit parse_factor_fit(const std::string& name) { return parse(kFits, name, "fit"); }
FactorDtype parse_factor_dtype(const std::string& name) { return parse(kDtypes, name, "dtype"); }

int Factors::rows() const {
    return layout == FactorLayout::HxDP ? grid.n_theta_h : grid.n_theta_h * grid.n_theta_d;
}
int Factors::columns() const {
    return layout == FactorLayout::HxDP ? grid.n_theta_d * grid.n_phi_d : grid.n_phi_d;
}

FactoredBrdf::FactoredBrdf(Factors factors) : f_(std::move(factors)) {
    f_.grid.validate();
    const std::size_t rows = static_cast<std::size_t>(f_.rows()), cols = static_cast<std::size_t>(f_.columns());
    if (f_.rank < 1 || static_cast<std::size_t>(f_.rank) > std::min(rows, cols))
        throw ValueError("factored: rank " + std::to_string(f_.rank) + " outside 1.." +
                         std::to_string(std::min(rows, cols)) + " for grid " + f_.grid.str() + " in layout " +
                         factor_layout_name(f_.layout));
    const std::size_t m = static_cast<std::size_t>(f_.row_width());
    const std::size_t colours = f_.colour == FactorColour::Shared ? 3 * static_cast<std::size_t>(f_.rank) : 0;
    if (f_.u.size() != rows * m || f_.v.size() != cols * m || f_.colour_weights.size() != colours)
        throw ValueError("factored: factor sizes " + std::to_string(f_.u.size()) + ", " + std::to_string(f_.v.size()) +
                         ", " + std::to_string(f_.colour_weights.size()) + " do not match " +
                         std::to_string(rows * m) + ", " + std::to_string(cols * m) + ", " + std::to_string(colours));
    for (const std::vector<float>* values : {&f_.u, &f_.v, &f_.colour_weights})
        for (float x : *values)
            if (!std::isfinite(x)) throw ValueError("factored: a factor entry is not finite");
    if (f_.dtype == FactorDtype::F16)
        for (std::vector<float>* values : {&f_.u, &f_.v})
            for (float& x : *values) {
                const Eigen::half h(x);
                if (!std::isfinite(static_cast<float>(h)))
                    throw ValueError("factored: a factor entry (" + std::to_string(x) + ") is beyond the float16 range");
                x = static_cast<float>(h);
            }
    for (int c = 0; c < 3; ++c) {
        const float top = f_.max_value[c];
        if (!(top >= 0.0f)) throw ValueError("factored: max_value " + std::to_string(top) + " is not a value >= 0");
        ceiling_[c] = to_space(f_.space, std::min(top, std::numeric_limits<float>::max()));
    }
    // The evaluation copies: rows padded to a whole number of the kernel's SIMD steps.
    avx2_ = detail::simd_level() == detail::Simd::Avx2Fma;
    const std::size_t step = lanes(avx2_ ? detail::Simd::Avx2Fma : detail::Simd::Sse2);
    width_ = (m + step - 1) / step * step;
    // U and V each from a 64-byte boundary: a row of 16 floats (separate colour to rank 5, shared to
    // rank 16, under AVX) then fills one cache line instead of straddling two.
    constexpr std::size_t kLine = 64 / sizeof(float);
    const std::size_t v_offset = (rows * width_ + kLine - 1) / kLine * kLine;
    storage_.assign(v_offset + cols * width_ + kLine - 1, 0.0f);
    float* u = storage_.data() + (kLine - reinterpret_cast<std::uintptr_t>(storage_.data()) / sizeof(float) % kLine) % kLine;
    float* v = u + v_offset;
    const bool grouped = grouped_channels(f_);
    const std::size_t rank = static_cast<std::size_t>(f_.rank);
    const auto copy_row = [&](const float* from, float* to) {
        if (grouped)
            for (std::size_t c = 0; c < 3; ++c) std::copy_n(from + c * rank, rank, to + 4 * c);
        else
            std::copy_n(from, m, to);
    };
    for (std::size_t i = 0; i < rows; ++i) copy_row(f_.u.data() + i * m, u + i * width_);
    for (std::size_t i = 0; i < cols; ++i) copy_row(f_.v.data() + i * m, v + i * width_);
    u_ = u;
    v_ = v;
    mix_.assign(3 * width_, 0.0f);
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t j = 0; j < static_cast<std::size_t>(f_.rank); ++j) {
            if (f_.colour == FactorColour::Shared)
                mix_[c * width_ + j] = f_.colour_weights[c * f_.rank + j];
            else
                mix_[c * width_ + c * f_.rank + j] = 1.0f;  // f_'s component order (reconstruct reads it)
        }
}

std::size_t FactoredBrdf::nbytes() const {
    const std::size_t entry = f_.dtype == FactorDtype::F16 ? 2 : sizeof(float);
    return (f_.u.size() + f_.v.size()) * entry + f_.colour_weights.size() * sizeof(float);
}

std::string FactoredBrdf::describe() const {
    char warp[48] = "";
    if (f_.grid.theta_d_warp != 0.0) std::snprintf(warp, sizeof warp, ", theta_d warp %g", f_.grid.theta_d_warp);
    return std::string(factor_method_name(f_.method)) + " rank " + std::to_string(f_.rank) + ", " +
           factor_space_name(f_.space) + " space, layout " + factor_layout_name(f_.layout) + ", " +
           factor_colour_name(f_.colour) + " colour, on " + f_.grid.str() + " (bin " +
           (f_.grid.position == BinPosition::Start ? "start" : "centre") +
           warp + (f_.dtype == FactorDtype::F16 ? "), float16 factors" : "), float32 factors");
}

Table FactoredBrdf::reconstruct(std::size_t* clamped) const {
    Table t(f_.grid, Table::Uninitialized{});
    const std::size_t cols = static_cast<std::size_t>(f_.columns()), m = static_cast<std::size_t>(f_.row_width());
    std::uint64_t count = 0;
    for (std::size_t bin = 0; bin < t.bins(); ++bin) {
        const float* u = f_.u.data() + bin / cols * m;
        const float* v = f_.v.data() + bin % cols * m;
        double y[3] = {0.0, 0.0, 0.0}, values[3];
        for (std::size_t j = 0; j < m; ++j) {
            const double p = static_cast<double>(u[j]) * v[j];
            for (std::size_t c = 0; c < 3; ++c) y[c] += mix_[c * width_ + j] * p;
        }
        for (int c = 0; c < 3; ++c) y[c] = std::min(y[c], ceiling_[c]);
        from_space_n(f_.space, y, values, 3, count);
        t.set(bin, {values[0], values[1], values[2]});
    }
    if (clamped) *clamped = count;
    return t;
}

// Above the L2 cache (512 KiB per core on the machines measured), the blends' factor rows miss it
// and are prefetched a block ahead; below, the prefetches only cost instructions. So do those of a
// factor within the L1 data cache (32 KiB), which stays there: the full grid's 90 θh rows (h_dp) or
// 180 φd rows (hd_p).
constexpr std::size_t kPrefetchBytes = 512 * 1024, kL1Bytes = 32 * 1024;

Rgb FactoredBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    Rgb f;
    eval_batch(&wi, &wo, &f, 1);
    return f;
}

void FactoredBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    std::uint64_t clamped = 0;
    const bool prefetch = storage_.size() * sizeof(float) > kPrefetchBytes;
    const std::size_t row_bytes = width_ * sizeof(float);
    // The float blend is clamped in float (the ceilings lie within the float range).
    const float ceiling[3] = {static_cast<float>(ceiling_[0]), static_cast<float>(ceiling_[1]),
                              static_cast<float>(ceiling_[2])};
    const FactorView view{f_.grid, width_, u_, v_, mix_.data(), ceiling,
                          prefetch && static_cast<std::size_t>(f_.rows()) * row_bytes > kL1Bytes,
                          prefetch && static_cast<std::size_t>(f_.columns()) * row_bytes > kL1Bytes,
                          grouped_channels(f_)};
    (view.grouped ? eval_kernel<true> : eval_kernel<false>)(avx2_ ? detail::Simd::Avx2Fma : detail::Simd::Sse2,
                                                            f_.layout, view, f_.space, wi, wo, out, n, clamped);
    if (clamped) clamped_.fetch_add(clamped, std::memory_order_relaxed);
}

const HalfVectorSampler& FactoredBrdf::sampler() const {
    return sampler_.get([this] { return std::make_unique<HalfVectorSampler>(*this); });
}

const FactorSampler& FactoredBrdf::factor_sampler() const {
    return factor_sampler_.get([this] { return std::make_unique<FactorSampler>(f_); });
}

BrdfSample FactoredBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    return sampler().sample(wo, u1, u2);
}

double FactoredBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return sampler().pdf(wo, wi); }

Factored factor(const Table& table, const FactorOptions& o) {
    const char* method = factor_method_name(o.method);
    Factors f;
    f.grid = table.grid();
    f.method = o.method;
    f.space = o.space;
    f.layout = o.layout;
    f.colour = o.colour;
    f.rank = o.rank;
    const int rows = f.rows(), cols = f.columns();
    if (o.rank < 1 || o.rank > std::min(rows, cols))
        throw ValueError(std::string(method) + ": rank " + std::to_string(o.rank) + " outside 1.." +
                         std::to_string(std::min(rows, cols)) + " for grid " + f.grid.str() + " in layout " +
                         factor_layout_name(o.layout));
    if (o.max_iterations < 1) throw ValueError(std::string(method) + ": the iteration cap must be at least 1");
    if (o.fit != FactorFit::Samples)
        throw ValueError(std::string(method) + ": fit=lsq fits the factors to the source's values between the "
                         "table's samples; give the source too (factor(source, table, options))");
    f.dtype = o.dtype;
    const bool nonneg = o.method == FactorMethod::Nmf;
    const bool shared = o.colour == FactorColour::Shared;
    const int k = o.rank, m = f.row_width();
    const int solves = shared ? 1 : 3;
    const auto step = [&](int solve_index) {
        return [&, solve_index](int it) {
            if (o.progress) o.progress(std::min(1.0, (solve_index + static_cast<double>(it) / o.max_iterations) / solves));
        };
    };

    FactorReport report;
    double objective = 0.0, norm = 0.0;
    f.u.assign(static_cast<std::size_t>(rows) * m, 0.0f);
    f.v.assign(static_cast<std::size_t>(cols) * m, 0.0f);
    report.converged = true;
    for (int solve_index = 0; solve_index < solves; ++solve_index) {
        const std::vector<int> channels = shared ? std::vector<int>{0, 1, 2} : std::vector<int>{solve_index};
        const Data d = prepare(table, o, rows, cols, channels);
        if (d.valid == 0) throw ValueError(std::string(method) + ": the table has no valid bins to factor");
        Solved r = solve(d, k, nonneg, o, step(solve_index));
        if (o.dtype == FactorDtype::F16) scale_for_f16(r, shared);  // FactoredBrdf rounds them
        report.valid_bins = d.valid;
        report.iterations = std::max(report.iterations, r.iterations);
        report.converged = report.converged && r.converged;
        objective += r.objective;
        norm += r.norm;
        const int offset = shared ? 0 : solve_index * k;  // separate: channel c's components at c·rank
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < k; ++j) f.u[static_cast<std::size_t>(i) * m + offset + j] = static_cast<float>(r.u(i, j));
        for (int i = 0; i < cols; ++i)
            for (int j = 0; j < k; ++j) f.v[static_cast<std::size_t>(i) * m + offset + j] = static_cast<float>(r.v(i, j));
        if (shared)
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < k; ++j) f.colour_weights.push_back(static_cast<float>(r.s(c, j)));
    }
    report.residual = norm > 0.0 ? std::sqrt(objective / norm) : 0.0;
    f.max_value = data_max(table);
    Factored out{std::make_unique<FactoredBrdf>(std::move(f)), report};
    out.brdf->reconstruct(&out.report.clamped);
    return out;
}

Factored factor(const Brdf& source, const Table& table, const FactorOptions& o) {
    if (o.fit == FactorFit::Samples) return factor(table, o);
    const char* method = factor_method_name(o.method);
    if (o.fit_iterations < 1) throw ValueError(std::string(method) + ": the refit's iteration cap must be at least 1");
    if (o.supersample < 1 || o.supersample > 16)
        throw ValueError(std::string(method) + ": fit=lsq's supersampling must be in [1, 16]");
    Factors shape;
    shape.grid = table.grid();
    shape.layout = o.layout;
    shape.colour = o.colour;
    shape.rank = o.rank;
    check_fit_size(shape, o.supersample, method);
    FactorOptions first = o;
    first.fit = FactorFit::Samples;
    first.dtype = FactorDtype::F32;
    if (o.progress) first.progress = [&o](double x) { o.progress(0.25 * x); };
    const Factored start = factor(table, first);
    Factors f = start.brdf->factors();
    FactorReport report = start.report;
    Solved r;
    refit(source, f, o, r, report, f.max_value);
    f.dtype = o.dtype;
    const bool shared = o.colour == FactorColour::Shared;
    const int m = f.row_width();
    for (int i = 0; i < f.rows(); ++i)
        for (int j = 0; j < m; ++j) f.u[static_cast<std::size_t>(i) * m + j] = static_cast<float>(r.u(i, j));
    for (int i = 0; i < f.columns(); ++i)
        for (int j = 0; j < m; ++j) f.v[static_cast<std::size_t>(i) * m + j] = static_cast<float>(r.v(i, j));
    if (shared)
        for (int c = 0; c < 3; ++c)
            for (int j = 0; j < f.rank; ++j)
                f.colour_weights[static_cast<std::size_t>(c) * f.rank + j] = static_cast<float>(r.s(c, j));
    Factored out{std::make_unique<FactoredBrdf>(std::move(f)), report};
    out.brdf->reconstruct(&out.report.clamped);
    return out;
}

}  // namespace brdfz
