#include "brdfz/brdf.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/simd.h"
#include "detail/simd.h"

namespace brdfz {

Simd simd_level() { return detail::simd_level(); }

const char* simd_name() {
    const detail::Simd level = detail::simd_level();
#if BRDFZ_X86
    return level == detail::Simd::Avx512 ? "avx512" : level == detail::Simd::Avx2Fma ? "avx2" : "sse2";
#elif defined(__aarch64__)
    return level == detail::Simd::Sve2 ? "sve2" : level == detail::Simd::Sve ? "sve" : "neon";
#else
    return "baseline";
#endif
}

namespace {

// Whether prepare_direction leaves every direction as it is (the batch kernels then take the caller's
// arrays directly).
bool all_prepared(const Vec3* v, std::size_t n) {
    bool ok = true;
    for (std::size_t k = 0; k < n; ++k) ok &= std::fabs(dot(v[k], v[k]) - 1.0) <= 1e-14;  // false for NaN
    return ok;
}

// Directions as the single-pair calls take them: prepared, an unusable one below the horizon, where
// every call gives 0 or a failed draw.
Vec3 prepared(Vec3 v) { return prepare_direction(v) ? v : Vec3{0.0, 0.0, -1.0}; }

// Runs kernel(a, b, k0, m) over [0, n) on the prepared directions, a slice at a time, so that the kernel
// finds in cache what the check has just read; a slice that needs preparing goes chunk by chunk through
// the stack.
template <typename Kernel>
void with_prepared(const Vec3* a, const Vec3* b, std::size_t n, Kernel&& kernel) {
    constexpr std::size_t kSlice = 4096, kChunk = 256;  // a slice's directions and results fit L2
    Vec3 pa[kChunk], pb[kChunk];
    for (std::size_t slice = 0; slice < n; slice += kSlice) {
        const std::size_t end = std::min(n, slice + kSlice);
        if (all_prepared(a + slice, end - slice) && (!b || all_prepared(b + slice, end - slice))) {
            kernel(a + slice, b ? b + slice : nullptr, slice, end - slice);
            continue;
        }
        for (std::size_t start = slice; start < end; start += kChunk) {
            const std::size_t m = std::min(kChunk, end - start);
            for (std::size_t k = 0; k < m; ++k) pa[k] = prepared(a[start + k]);
            if (b)
                for (std::size_t k = 0; k < m; ++k) pb[k] = prepared(b[start + k]);
            kernel(pa, b ? pb : nullptr, start, m);
        }
    }
}

}  // namespace

Rgb Brdf::eval_cos(const Vec3& wi, const Vec3& wo) const {
    Rgb f = eval(wi, wo);
    const Vec3 a = prepared(wi);
    for (double& c : f) c *= a.z > 0.0 ? a.z : 0.0;
    return f;
}

void Brdf::eval(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const {
    if (wi.size() != wo.size() || wi.size() != out.size())
        throw ValueError("eval: batch sizes differ (wi " + std::to_string(wi.size()) + ", wo " +
                         std::to_string(wo.size()) + ", out " + std::to_string(out.size()) + ")");
    with_prepared(wi.data(), wo.data(), wi.size(), [&](const Vec3* a, const Vec3* b, std::size_t k0, std::size_t m) {
        eval_batch(a, b, out.data() + k0, m);
    });
}

void Brdf::eval_cos(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const {
    eval(wi, wo, out);
    for (std::size_t k = 0; k < out.size(); ++k) {
        const Vec3 a = prepared(wi[k]);
        const double c = a.z > 0.0 ? a.z : 0.0;
        for (double& v : out[k]) v *= c;
    }
}

void Brdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    for (std::size_t k = 0; k < n; ++k) out[k] = eval(wi[k], wo[k]);
}

BrdfSample Brdf::draw(const Vec3& wo, double u1, double u2) const {
    if (!can_draw(wo, u1, u2)) return {};
    const BrdfSample s = sample_above(wo, u1, u2);
    return usable(s) ? s : BrdfSample{};
}

namespace {
// A sampler that knows f sets the weight itself; otherwise it is left to the caller.
bool needs_weight(const BrdfSample& s) { return s.pdf > 0.0 && s.weight == Rgb{0.0, 0.0, 0.0}; }
void set_weight(BrdfSample& s, const Rgb& f) {
    for (int c = 0; c < 3; ++c) s.weight[c] = f[c] * s.wi.z / s.pdf;
}
}  // namespace

BrdfSample Brdf::sample(const Vec3& wo, double u1, double u2) const {
    const Vec3 v = prepared(wo);
    BrdfSample s = draw(v, u1, u2);
    if (needs_weight(s)) set_weight(s, eval_above(s.wi, v));
    return s;
}

double Brdf::pdf(const Vec3& wo, const Vec3& wi) const {
    Vec3 a = wo, b = wi;
    if (!prepare_direction(a) || !prepare_direction(b) || !(a.z > 0.0 && b.z > 0.0)) return 0.0;
    return pdf_above(a, b);
}

void Brdf::sample(std::span<const Vec3> wo, std::span<const std::array<double, 2>> u,
                  std::span<BrdfSample> out) const {
    if (wo.size() != u.size() || wo.size() != out.size())
        throw ValueError("sample: batch sizes differ (wo " + std::to_string(wo.size()) + ", u " +
                         std::to_string(u.size()) + ", out " + std::to_string(out.size()) + ")");
    with_prepared(wo.data(), nullptr, wo.size(), [&](const Vec3* a, const Vec3*, std::size_t k0, std::size_t m) {
        sample_batch(a, u.data() + k0, out.data() + k0, m);
    });
}

void Brdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    // Draw a block, then evaluate the weights it needs in one batch (eval_batch is the fast kernel).
    constexpr std::size_t kBlock = 64;
    Vec3 wi[kBlock], wos[kBlock];
    Rgb f[kBlock];
    std::size_t slot[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        std::size_t pending = 0;
        for (std::size_t k = 0; k < m; ++k) {
            BrdfSample& s = out[start + k] = draw(wo[start + k], u[start + k][0], u[start + k][1]);
            if (!needs_weight(s)) continue;
            wi[pending] = s.wi, wos[pending] = wo[start + k], slot[pending++] = start + k;
        }
        eval_batch(wi, wos, f, pending);
        for (std::size_t j = 0; j < pending; ++j) set_weight(out[slot[j]], f[j]);
    }
}

void Brdf::pdf(std::span<const Vec3> wo, std::span<const Vec3> wi, std::span<double> out) const {
    if (wo.size() != wi.size() || wo.size() != out.size())
        throw ValueError("pdf: batch sizes differ (wo " + std::to_string(wo.size()) + ", wi " +
                         std::to_string(wi.size()) + ", out " + std::to_string(out.size()) + ")");
    with_prepared(wo.data(), wi.data(), wo.size(), [&](const Vec3* a, const Vec3* b, std::size_t k0, std::size_t m) {
        pdf_batch(a, b, out.data() + k0, m);
    });
}

void Brdf::pdf_batch(const Vec3* wo, const Vec3* wi, double* out, std::size_t n) const {
    for (std::size_t k = 0; k < n; ++k) out[k] = pdf(wo[k], wi[k]);
}

BrdfSample Brdf::sample_above(const Vec3&, double u1, double u2) const {
    const Vec3 wi = cosine_hemisphere(u1, u2);
    return {wi, wi.z / std::numbers::pi, {}};
}

double Brdf::pdf_above(const Vec3&, const Vec3& wi) const { return wi.z / std::numbers::pi; }

}  // namespace brdfz
