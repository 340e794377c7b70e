// A material read through brdfz::runtime, as a Brdf: what load() gives for a .brdfzrt file, and what
// the writer copies as it is.
#pragma once

#include "brdfz/brdf.h"
#include "brdfz/runtime/runtime.h"

namespace brdfz::formats {

class RuntimeBrdf final : public Brdf {
public:
    explicit RuntimeBrdf(runtime::Material m) : m_(std::move(m)) {}
    int channels() const override { return 3; }
    std::size_t nbytes() const override { return m_.nbytes(); }
    std::string describe() const override { return "runtime layout of " + m_.describe(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override { return m_.eval(wi, wo); }
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override {
        const runtime::Sample64 s = m_.sample(wo, u1, u2);
        return {s.wi, s.pdf, s.weight};
    }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return m_.pdf(wo, wi); }

public:
    const runtime::Material& material() const { return m_; }

private:
    runtime::Material m_;
};

}  // namespace brdfz::formats
