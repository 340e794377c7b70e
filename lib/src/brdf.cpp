#include "brdfz/brdf.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"

namespace brdfz {

Rgb Brdf::eval_cos(const Vec3& wi, const Vec3& wo) const {
    Rgb f = eval(wi, wo);
    for (double& c : f) c *= wi.z > 0.0 ? wi.z : 0.0;
    return f;
}

void Brdf::eval(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const {
    if (wi.size() != wo.size() || wi.size() != out.size())
        throw ValueError("eval: batch sizes differ (wi " + std::to_string(wi.size()) + ", wo " +
                         std::to_string(wo.size()) + ", out " + std::to_string(out.size()) + ")");
    eval_batch(wi.data(), wo.data(), out.data(), wi.size());
}

void Brdf::eval_cos(std::span<const Vec3> wi, std::span<const Vec3> wo, std::span<Rgb> out) const {
    eval(wi, wo, out);
    for (std::size_t k = 0; k < out.size(); ++k) {
        const double c = wi[k].z > 0.0 ? wi[k].z : 0.0;
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
    BrdfSample s = draw(wo, u1, u2);
    if (needs_weight(s)) set_weight(s, eval_above(s.wi, wo));
    return s;
}

double Brdf::pdf(const Vec3& wo, const Vec3& wi) const {
    if (!(wo.z > 0.0 && wi.z > 0.0)) return 0.0;
    return pdf_above(wo, wi);
}

void Brdf::sample(std::span<const Vec3> wo, std::span<const std::array<double, 2>> u,
                  std::span<BrdfSample> out) const {
    if (wo.size() != u.size() || wo.size() != out.size())
        throw ValueError("sample: batch sizes differ (wo " + std::to_string(wo.size()) + ", u " +
                         std::to_string(u.size()) + ", out " + std::to_string(out.size()) + ")");
    sample_batch(wo.data(), u.data(), out.data(), wo.size());
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
    for (std::size_t k = 0; k < wo.size(); ++k) out[k] = pdf(wo[k], wi[k]);
}

BrdfSample Brdf::sample_above(const Vec3&, double u1, double u2) const {
    const Vec3 wi = cosine_hemisphere(u1, u2);
    return {wi, wi.z / std::numbers::pi, {}};
}

double Brdf::pdf_above(const Vec3&, const Vec3& wi) const { return wi.z / std::numbers::pi; }

}  // namespace brdfz
