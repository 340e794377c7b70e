#include "rows.h"

#include <cmath>
#include <limits>

namespace brdfz::python {
namespace {

template <typename T>
std::size_t normalise(const T* xyz, std::size_t begin, std::span<Vec3> out) {
    // Branch-free and indexed (not a pointer per row), so the loop vectorises; the bad rows are counted
    // in a double (an integer or bool reduction beside doubles does not vectorise), and the first one is
    // looked for only when there is one.
    const T* p = xyz + 3 * begin;
    double bad = 0.0;
    for (std::size_t k = 0; k < out.size(); ++k) {
        const Vec3 d{p[3 * k], p[3 * k + 1], p[3 * k + 2]};
        const double n = length(d);
        bad += (n > 0.0) & (n < std::numeric_limits<double>::infinity()) ? 0.0 : 1.0;
        out[k] = (1.0 / n) * d;
    }
    if (bad == 0.0) return out.size();
    for (std::size_t k = 0; k < out.size(); ++k) {
        const T* v = xyz + 3 * (begin + k);
        const double n = length(Vec3{v[0], v[1], v[2]});
        if (!(std::isfinite(n) && n != 0.0)) return k;
    }
    return out.size();
}

template <typename T>
void copy(const T* u, std::size_t begin, std::span<std::array<double, 2>> out) {
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = {u[2 * (begin + k)], u[2 * (begin + k) + 1]};
}

}  // namespace

// Built for the x86-64 baseline and for AVX2 and AVX-512, chosen at load (an ifunc): the square roots
// and divisions take a share of a batch eval's time at two doubles per instruction. IEEE sqrt and
// division, and no FMA contraction (CMakeLists.txt), give the same bits in every build.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define BRDFZ_ROWS_CLONES [[gnu::target_clones("default", "avx2", "arch=x86-64-v4")]]
#else
#define BRDFZ_ROWS_CLONES
#endif
BRDFZ_ROWS_CLONES std::size_t normalise_rows(const float* xyz, std::size_t begin, std::span<Vec3> out) {
    return normalise(xyz, begin, out);
}
BRDFZ_ROWS_CLONES std::size_t normalise_rows(const double* xyz, std::size_t begin, std::span<Vec3> out) {
    return normalise(xyz, begin, out);
}
void copy_rows(const float* u, std::size_t begin, std::span<std::array<double, 2>> out) { copy(u, begin, out); }
void copy_rows(const double* u, std::size_t begin, std::span<std::array<double, 2>> out) { copy(u, begin, out); }

void split_samples(std::span<const BrdfSample> s, std::size_t begin, double* wi, double* pdf, double* weight) {
    for (std::size_t k = 0; k < s.size(); ++k) {
        const std::size_t j = begin + k;
        wi[3 * j] = s[k].wi.x, wi[3 * j + 1] = s[k].wi.y, wi[3 * j + 2] = s[k].wi.z;
        pdf[j] = s[k].pdf;
        for (int c = 0; c < 3; ++c) weight[3 * j + c] = s[k].weight[c];
    }
}

}  // namespace brdfz::python
