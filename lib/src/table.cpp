#include "brdfz/table.h"

#include <cstring>
#include <limits>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "brdfz/errors.h"

namespace brdfz {

void GridSpec::validate() const {
    for (int n : {n_theta_h, n_theta_d, n_phi_d})
        if (n < 1 || n > kMaxAxis)
            throw ValueError("grid " + str() + ": every axis must be in [1, " + std::to_string(kMaxAxis) + "]");
    if (bins() > kMaxBins)
        throw ValueError("grid " + str() + ": " + std::to_string(bins()) + " bins, a float32 table of " +
                         std::to_string(3 * sizeof(float) * bins()) + " bytes, over the limit of " +
                         std::to_string(kMaxBins) + " bins (" + std::to_string(3 * sizeof(float) * kMaxBins) + " bytes)");
    if (symmetry != Symmetry::Reciprocal && symmetry != Symmetry::None && symmetry != Symmetry::Bilateral)
        throw ValueError("grid " + str() + ": unknown phi_d symmetry");
    if (!(theta_d_warp >= 0.0 && theta_d_warp <= kMaxWarp))
        throw ValueError("grid " + str() + ": theta_d warp " + std::to_string(theta_d_warp) + " outside [0, 0.95]");
    if (!(theta_h_warp == 0.0 || (theta_h_warp >= kMinThetaHWarp && theta_h_warp <= kMaxThetaHWarp)))
        throw ValueError("grid " + str() + ": theta_h warp " + std::to_string(theta_h_warp * 180.0 / std::numbers::pi) +
                         " degrees: 0 or in [0.01, 45]");
}

double axis::u_to_theta_d(double u, int n, double w) {
    if (w == 0.0) return u_to_theta_d(u, n);
    const double x = u / n;
    double lo = 0.0, hi = std::numbers::pi / 2.0;
    if (!(x > 0.0)) return 0.0;
    if (!(x < 1.0)) return hi;
    for (int i = 0; i < 60; ++i) {  // 2^-60 of π/2: below double rounding
        const double mid = 0.5 * (lo + hi);
        (theta_d_to_u(mid, 1, w) < x ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

const char* symmetry_name(Symmetry s) {
    switch (s) {
        case Symmetry::Reciprocal: return "reciprocal";
        case Symmetry::Bilateral: return "bilateral";
        default: return "none";
    }
}

Symmetry parse_symmetry(const std::string& name) {
    if (name == "reciprocal") return Symmetry::Reciprocal;
    if (name == "none") return Symmetry::None;
    if (name == "bilateral") return Symmetry::Bilateral;
    throw ValueError("symmetry must be 'reciprocal', 'none' or 'bilateral', not '" + name + "'");
}

std::string GridSpec::str() const {
    return std::to_string(n_theta_h) + "x" + std::to_string(n_theta_d) + "x" + std::to_string(n_phi_d);
}

namespace {
constexpr std::size_t kHugePage = std::size_t{2} << 20;
// Below two huge pages a table gains little from them, and the 2 MiB alignment could waste as much again.
bool huge(std::size_t bytes) { return bytes >= 2 * kHugePage; }
}  // namespace

void* table_memory_allocate(std::size_t bytes) {
    const std::size_t total = bytes + kTablePadding;
    if (total < bytes) throw std::bad_array_new_length();
    void* p = huge(bytes) ? ::operator new(total, std::align_val_t{kHugePage}) : ::operator new(total);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Advice only: where huge pages are off or unavailable the memory stays on small pages.
    if (huge(bytes)) madvise(p, total, MADV_HUGEPAGE);
#endif
    std::memset(static_cast<char*>(p) + bytes, 0, kTablePadding);
    return p;
}

void table_memory_free(void* p, std::size_t bytes) {
    if (huge(bytes))
        ::operator delete(p, std::align_val_t{kHugePage});
    else
        ::operator delete(p);
}

Table::Table(GridSpec grid) : grid_(grid) {
    grid_.validate();
    values_.assign(3 * grid_.bins(), std::numeric_limits<float>::quiet_NaN());
}

Table::Table(GridSpec grid, Uninitialized) : grid_(grid) {
    grid_.validate();
    values_.resize(3 * grid_.bins());
}

bool Table::valid(std::size_t bin) const {
    const float* v = &values_[3 * bin];
    return !std::isnan(v[0]) && !std::isnan(v[1]) && !std::isnan(v[2]);
}

void Table::set(std::size_t bin, const Rgb& f) {
    for (int c = 0; c < 3; ++c) values_[3 * bin + c] = static_cast<float>(f[c]);
}

void Table::invalidate(std::size_t bin) {
    for (int c = 0; c < 3; ++c) values_[3 * bin + c] = std::numeric_limits<float>::quiet_NaN();
}

std::size_t Table::valid_bins() const {
    std::size_t n = 0;
    for (std::size_t b = 0; b < bins(); ++b) n += valid(b);
    return n;
}

bool Table::operator==(const Table& other) const {
    return grid_ == other.grid_ && std::memcmp(values_.data(), other.values_.data(), values_.size() * sizeof(float)) == 0;
}

}  // namespace brdfz
