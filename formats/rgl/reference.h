// RglBrdf's scalar reference: Mitsuba 3's `measured` in double, one pair at a time, with libm's asin,
// atan2, sin and cos, std::lower_bound and the reader's tables rebuilt from the tensors. The
// specification that the batch kernels (kernels.cpp, each of its Highway builds) are tested against
// (tests/formats/rgl_kernel_test.cpp): they differ from it by their polynomial arctangent and sine
// table, within 1e-8 (rgl.h).
#pragma once

#include <memory>

#include "brdfz/formats/rgl.h"
#include "rgl/marginal2d.h"
#include "rgl/scalar_warp.h"

namespace brdfz::rgl::detail {

class Reference {
public:
    explicit Reference(const RglBrdf& b);
    Rgb eval(const Vec3& wi, const Vec3& wo) const;
    double pdf(const Vec3& wo, const Vec3& wi) const;
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;

private:
    Tensors t_;
    Marginal2D vndf_;
    std::unique_ptr<Marginal2D> lum_;
};

}  // namespace brdfz::rgl::detail
