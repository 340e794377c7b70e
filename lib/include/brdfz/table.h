// A regular Rusinkiewicz grid over (θh, θd, φd) and a float32 RGB table on it.
//
// Axes (MERL's, at any resolution):
//   θh ∈ [0, π/2) on a square-root axis: bin i covers [(i/n)²·π/2, ((i+1)/n)²·π/2);
//   θd ∈ [0, π/2) linear, or optionally warped towards grazing (GridSpec::theta_d_warp);
//   φd ∈ [0, π) linear, folded by reciprocity (φd ~ φd + π: the pair with wi and wo exchanged), or with
//   Symmetry::None ∈ [0, 2π) linear, for data whose f(wi, wo) differs from f(wo, wi) (real RGL
//   measurements at grazing angles), or with Symmetry::Bilateral ∈ [0, π] linear, folded by the mirror
//   y → −y (φd ~ −φd at φh = 0), which every isotropic material has, reciprocal or not.
// Bin index = φd + nφd·(θd + nθd·θh), MERL's order.
// Nearest lookup is floor() of the continuous bin coordinate with MERL's exact arithmetic, so it picks
// bit-identically the bin MERL's published lookup picks. Where each bin's value sits for
// interpolation (its start or its centre) is the explicit BinPosition option.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <numbers>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/runtime/kernels/grid.h"

namespace brdfz {

// Where a bin's sample sits along each axis, for interpolation and tabulation. Centre (the default)
// reads a value as its bin's average, which is how MERL measurements were binned, and makes MERL's
// floor() lookup the nearest sample; Start puts sample i at the bin's lower edge (θh = 0 is then
// sampled exactly), as some published MERL tools assume.
enum class BinPosition { Start, Centre };

// Named axis maps: angle -> continuous bin coordinate in [0, n] and back. The forward maps use
// MERL's operation order (theta_half_index and friends) so floor() matches it bit for bit.
namespace axis {
// The forward maps are the runtime's (brdfz/runtime/kernels/grid.h: the lookups' one source).
using runtime::kernels::axis::bilateral_phi_d_to_u;
using runtime::kernels::axis::full_phi_d_to_u;
using runtime::kernels::axis::phi_d_to_u;
using runtime::kernels::axis::theta_d_to_u;
using runtime::kernels::axis::theta_h_to_u;
inline double u_to_theta_h(double u, int n) { return (u / n) * (u / n) * (std::numbers::pi / 2.0); }
// Inverse of the θh axis warped by s (theta_h_to_u(θh, n, s)); s = 0 the square-root axis.
inline double u_to_theta_h(double u, int n, double s) {
    if (s == 0.0) return u_to_theta_h(u, n);
    const double t = u / n * ((std::numbers::pi / 2.0) / (std::numbers::pi / 2.0 + s));
    return s * t / (1.0 - t);
}
// dθh/du on the θh axis warped by s, in units of π/n²: on the square-root axis (s = 0) u itself.
inline double theta_h_slope(double u, int n, double s) {
    if (s == 0.0) return u;
    const double c = (std::numbers::pi / 2.0) / (std::numbers::pi / 2.0 + s), t = u / n * c;
    return s * c * n / (std::numbers::pi * (1.0 - t) * (1.0 - t));
}
// How much more θh a bin at u spans than a bin of the square-root axis at the same θh: 1 when s = 0.
inline double theta_h_density(double u, int n, double s) {
    if (s == 0.0) return 1.0;
    return theta_h_slope(u, n, s) / (n * std::sqrt(u_to_theta_h(u, n, s) * (2.0 / std::numbers::pi)));
}
inline double u_to_theta_d(double u, int n) { return u / n * (std::numbers::pi / 2.0); }
// Inverse of the warped map by bisection (it is increasing): setup only, never in a lookup.
double u_to_theta_d(double u, int n, double w);
inline double u_to_phi_d(double u, int n) { return u / n * std::numbers::pi; }
inline double u_to_full_phi_d(double u, int n) { return u / n * (2.0 * std::numbers::pi); }
// Nearest bin of a coordinate: floor, clamped to [0, n-1]; NaN goes to 0 (fmax drops NaN) so the
// int conversion is always defined.
inline int bin_of(double u, int n) { return static_cast<int>(std::fmin(std::fmax(u, 0.0), n - 1.0)); }
}  // namespace axis

// What the φd axis folds (see the top of this file). Reciprocal: f(wi, wo) and f(wo, wi) share a bin;
// a non-reciprocal source is tabulated as the mean of the two (tabulate.h). None: φd over [0, 2π).
// Bilateral: the pair and its mirror image (y → −y) share a bin; a source not mirror-symmetric
// (Brdf::bilateral) is tabulated as the mean of the two. Its spec word is the one a φh axis's mirror
// fold has (repr/phi_h.h): without a φh axis the mirror folds φd.
enum class Symmetry { Reciprocal, None, Bilateral };
const char* symmetry_name(Symmetry s);            // "reciprocal", "none", "bilateral"
Symmetry parse_symmetry(const std::string& name);  // ValueError otherwise

struct GridSpec {
    int n_theta_h = 90;
    int n_theta_d = 90;
    int n_phi_d = 180;
    BinPosition position = BinPosition::Centre;
    double theta_d_warp = 0.0;  // axis::theta_d_to_u's w; 0: MERL's linear θd axis
    Symmetry symmetry = Symmetry::Reciprocal;
    double theta_h_warp = 0.0;  // axis::theta_h_to_u's s, radians; 0: MERL's square-root θh axis

    static constexpr int kMaxAxis = 4096;  // bound on any axis, checked before allocating
    // Bound on the bins of any grid, checked before allocating: 2^26 bins, a float32 RGB table of
    // 805,306,368 bytes (MERL's 90x90x180 has 1,458,000 bins).
    static constexpr std::size_t kMaxBins = std::size_t{1} << 26;
    static constexpr double kMaxWarp = 0.95;  // the first θd bin 11° wide at 40 bins (linear: 2.25°)
    // Bounds of theta_h_warp (radians, when not 0): 0.01° to 45°.
    static constexpr double kMinThetaHWarp = 0.01 * std::numbers::pi / 180.0, kMaxThetaHWarp = std::numbers::pi / 4.0;

    std::size_t bins() const {
        return static_cast<std::size_t>(n_theta_h) * n_theta_d * n_phi_d;
    }
    std::size_t index(int ih, int id, int ip) const {
        return static_cast<std::size_t>(ip) + static_cast<std::size_t>(n_phi_d) * (id + static_cast<std::size_t>(n_theta_d) * ih);
    }
    // Offset of a bin's sample from its start, in bins.
    double sample_offset() const { return position == BinPosition::Centre ? 0.5 : 0.0; }
    // Angles at which bin (ih, id, ip) is sampled.
    double theta_h_at(int ih) const { return theta_h_of_u(ih + sample_offset()); }
    double theta_h_of_u(double u) const { return axis::u_to_theta_h(u, n_theta_h, theta_h_warp); }
    double theta_h_to_u(double theta_h) const { return axis::theta_h_to_u(theta_h, n_theta_h, theta_h_warp); }
    double theta_d_at(int id) const { return axis::u_to_theta_d(id + sample_offset(), n_theta_d, theta_d_warp); }
    double theta_d_to_u(double theta_d) const { return axis::theta_d_to_u(theta_d, n_theta_d, theta_d_warp); }
    double phi_d_at(int ip) const {
        return full_circle() ? axis::u_to_full_phi_d(ip + sample_offset(), n_phi_d)
                             : axis::u_to_phi_d(ip + sample_offset(), n_phi_d);
    }
    // φd in (-π, π] -> continuous bin coordinate in [0, n_phi_d].
    double phi_d_to_u(double phi_d) const {
        return full_circle() ? axis::full_phi_d_to_u(phi_d, n_phi_d)
               : bilateral() ? axis::bilateral_phi_d_to_u(phi_d, n_phi_d)
                             : axis::phi_d_to_u(phi_d, n_phi_d);
    }
    bool reciprocal() const { return symmetry == Symmetry::Reciprocal; }
    bool bilateral() const { return symmetry == Symmetry::Bilateral; }
    // φd over [0, 2π) (Symmetry::None); the other two fold it onto [0, π].
    bool full_circle() const { return symmetry == Symmetry::None; }
    double phi_d_range() const { return full_circle() ? 2.0 * std::numbers::pi : std::numbers::pi; }
    // Throws ValueError unless every axis is in [1, kMaxAxis], bins() <= kMaxBins (the message gives
    // the table's bytes), theta_h_warp 0 or in [kMinThetaHWarp, kMaxThetaHWarp] and theta_d_warp in
    // [0, kMaxWarp].
    void validate() const;
    std::string str() const;  // "90x90x180"
    bool operator==(const GridSpec&) const = default;
};

// How many bins a source had in each class. A bin is valid when all its channels are finite and >= 0;
// an invalid bin is counted in every class one of its channels falls in.
struct ValidityCounts {
    std::size_t valid = 0;
    std::size_t negative = 0;
    std::size_t nan = 0;
    std::size_t inf = 0;
    std::size_t clamped = 0;        // bins with negative values set to 0 instead (tabulation policy)
    std::size_t below_horizon = 0;  // bins whose wi or wo is below the horizon (left invalid)
};

// Memory for a table's values, with kTablePadding zero bytes after the requested ones, so that lookups
// may read a bin's three floats as one vector of four. Blocks of 4 MiB and more are 2 MiB-aligned and,
// on Linux, marked for transparent huge pages: lookups and the sampler's weights land anywhere in a
// 17 MB table, and on 4 KiB pages most of them would also miss the TLB.
constexpr std::size_t kTablePadding = 16;
void* table_memory_allocate(std::size_t bytes);
void table_memory_free(void* p, std::size_t bytes);  // the same `bytes` as allocated

// float32 RGB values interleaved per bin (one cache line per lookup, not three). A channel that is
// not valid holds a quiet NaN: that is the validity mask, and lookups skip those entries.
class Table {
public:
    explicit Table(GridSpec grid);  // every value invalid
    // Values left unset, for readers that write every entry (saves a pass over the table on load).
    struct Uninitialized {};
    Table(GridSpec grid, Uninitialized);

    const GridSpec& grid() const { return grid_; }
    std::size_t bins() const { return grid_.bins(); }

    float* data() { return values_.data(); }
    const float* data() const { return values_.data(); }

    float at(std::size_t bin, int channel) const { return values_[3 * bin + channel]; }
    bool valid(std::size_t bin) const;
    void set(std::size_t bin, const Rgb& f);
    void invalidate(std::size_t bin);

    // Counts of the current contents (valid bins vs bins with a NaN marker).
    std::size_t valid_bins() const;

    bool operator==(const Table& other) const;  // same grid and bit-identical values

private:
    // Leaves new elements default-initialised (unset) instead of zeroing them, and puts large tables
    // on huge pages (table_memory_allocate).
    template <typename T>
    struct TableAllocator {
        using value_type = T;
        TableAllocator() = default;
        template <typename U>
        TableAllocator(const TableAllocator<U>&) {}
        T* allocate(std::size_t n) { return static_cast<T*>(table_memory_allocate(n * sizeof(T))); }
        void deallocate(T* p, std::size_t n) { table_memory_free(p, n * sizeof(T)); }
        template <typename U>
        void construct(U* p) {
            ::new (static_cast<void*>(p)) U;
        }
        template <typename U, typename... Args>
        void construct(U* p, Args&&... args) {
            ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
        }
        template <typename U>
        bool operator==(const TableAllocator<U>&) const {
            return true;
        }
    };

    GridSpec grid_;
    std::vector<float, TableAllocator<float>> values_;
};

}  // namespace brdfz
