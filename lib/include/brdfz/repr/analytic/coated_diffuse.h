// A built-in analytic material: a rough dielectric coat (GGX, exact Fresnel) over a coloured
// Lambertian base. It is the embedded default of `brdfz demo` and a known answer for tests.
//   f = F(wi·h) D(h) G2(wi, wo) / (4 cosθi cosθo)  +  (1 − F(cosθi)) (1 − F(cosθo)) ρ / π
// Reciprocal, and energy-conserving for the default parameters (checked by tests).
#pragma once

#include <string>

#include "brdfz/brdf.h"

namespace brdfz {

struct CoatedDiffuseParams {
    Rgb base_albedo{0.60, 0.25, 0.08};
    double alpha = 0.12;  // GGX roughness of the coat
    double eta = 1.5;     // coat refractive index
};

class CoatedDiffuse final : public Brdf {
public:
    explicit CoatedDiffuse(CoatedDiffuseParams p = {});

    const CoatedDiffuseParams& params() const { return p_; }
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return 5 * sizeof(double); }  // ρ (3), α, η
    std::string describe() const override;

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;

private:
    CoatedDiffuseParams p_;
};

}  // namespace brdfz
