#include "brdfz/brdf.h"

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

}  // namespace brdfz
