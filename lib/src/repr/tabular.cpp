#include "brdfz/repr/tabular.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <numbers>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "detail/bin_coords.h"

namespace brdfz {
namespace {

using namespace detail;

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
[[gnu::noinline]] std::size_t exact_nearest_bin(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const BinCoords c = bin_coords(g, wi, wo);
    return g.index(bin_of(c.uh, g.n_theta_h), bin_of(c.ud, g.n_theta_d), bin_of(c.up, g.n_phi_d));
}

// The nearest bin given the pair's fast coordinates.
inline std::size_t nearest_bin(const GridSpec& g, const BinCoords& c, const Vec3& wi, const Vec3& wo) {
    int ih, id, ip;
    const bool ch = clear_bin(c.uh, g.n_theta_h, ih), cd = clear_bin(c.ud, g.n_theta_d, id),
               cp = clear_bin(c.up, g.n_phi_d, ip);
    return (ch & cd & cp) ? g.index(ih, id, ip) : exact_nearest_bin(g, wi, wo);
}

inline Rgb read_nearest(const float* v) {
    Rgb f;
    for (int ch = 0; ch < 3; ++ch) f[ch] = std::isnan(v[ch]) ? 0.0 : v[ch];
    return f;
}

inline Rgb read_linear(const Table& t, const Corners& k) {
    const GridSpec& g = t.grid();
    double sum[3] = {0, 0, 0}, wsum[3] = {0, 0, 0};
    for (int a = 0; a < 2; ++a) {
        const int ih = a ? k.h.i1 : k.h.i0;
        const double wa = a ? k.h.t : 1.0 - k.h.t;
        for (int b = 0; b < 2; ++b) {
            const int id = b ? k.d.i1 : k.d.i0;
            const double wb = wa * (b ? k.d.t : 1.0 - k.d.t);
            for (int p = 0; p < 2; ++p) {
                const double w = wb * (p ? k.p.t : 1.0 - k.p.t);
                const float* v = t.data() + 3 * g.index(ih, id, p ? k.p.i1 : k.p.i0);
                for (int ch = 0; ch < 3; ++ch) {
                    // Invalid samples are NaN: they contribute neither value nor weight.
                    const bool ok = v[ch] == v[ch];
                    sum[ch] += ok ? w * v[ch] : 0.0;
                    wsum[ch] += ok ? w : 0.0;
                }
            }
        }
    }
    Rgb f;
    for (int ch = 0; ch < 3; ++ch) f[ch] = wsum[ch] > 0.0 ? sum[ch] / wsum[ch] : 0.0;
    return f;
}

}  // namespace

Lookup parse_lookup(const std::string& name) {
    if (name == "nearest") return Lookup::Nearest;
    if (name == "linear") return Lookup::Linear;
    throw ValueError("unknown lookup '" + name + "' (expected nearest or linear)");
}

const char* lookup_name(Lookup lookup) { return lookup == Lookup::Nearest ? "nearest" : "linear"; }

TabularBrdf::TabularBrdf(Table table, Lookup lookup) : table_(std::move(table)), lookup_(lookup) {}

std::string TabularBrdf::describe() const {
    return "tabular " + table_.grid().str() + " float32, bin " +
           (table_.grid().position == BinPosition::Start ? "start" : "centre") + ", " + lookup_name(lookup_) +
           " lookup";
}

Rgb TabularBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    const GridSpec& g = table_.grid();
    const BinCoords c = fast_bin_coords(g, wi, wo);
    if (lookup_ == Lookup::Nearest) return read_nearest(table_.data() + 3 * nearest_bin(g, c, wi, wo));
    return read_linear(table_, linear_corners(g, c, wi, wo));
}

// Blocks of pairs in three passes: (1) the coordinates, branch-free and vectorised; (2) bins or
// corners, prefetching the table lines; (3) the table reads. In one pass a lookup's arithmetic is too
// long for the core to run ahead to the next pair's table read, so every cache miss stalled in turn.
void TabularBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    constexpr std::size_t kBlock = 64;
    const GridSpec& g = table_.grid();
    const float* data = table_.data();
    BinCoords coords[kBlock];
    std::size_t bins[kBlock];
    Corners corners[kBlock];
    bool above[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        const Vec3* a = wi + start;
        const Vec3* b = wo + start;
        for (std::size_t k = 0; k < m; ++k) coords[k] = fast_bin_coords(g, a[k], b[k]);
        for (std::size_t k = 0; k < m; ++k) above[k] = (a[k].z > 0.0) & (b[k].z > 0.0);
        if (lookup_ == Lookup::Nearest) {
            for (std::size_t k = 0; k < m; ++k) {
                if (!above[k]) continue;
                bins[k] = nearest_bin(g, coords[k], a[k], b[k]);
                __builtin_prefetch(data + 3 * bins[k]);
            }
            for (std::size_t k = 0; k < m; ++k) out[start + k] = above[k] ? read_nearest(data + 3 * bins[k]) : Rgb{};
        } else {
            for (std::size_t k = 0; k < m; ++k) {
                if (!above[k]) continue;
                const Corners& c = corners[k] = linear_corners(g, coords[k], a[k], b[k]);
                for (int ih : {c.h.i0, c.h.i1})
                    for (int id : {c.d.i0, c.d.i1}) __builtin_prefetch(data + 3 * g.index(ih, id, c.p.i0));
            }
            for (std::size_t k = 0; k < m; ++k) out[start + k] = above[k] ? read_linear(table_, corners[k]) : Rgb{};
        }
    }
}

const HalfVectorSampler& TabularBrdf::sampler() const {
    return sampler_.get([this] { return std::make_unique<HalfVectorSampler>(*this); });
}

BrdfSample TabularBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    return sampler().sample(wo, u1, u2);
}

double TabularBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return sampler().pdf(wo, wi); }

}  // namespace brdfz
