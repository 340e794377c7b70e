// brdfz::runtime: evaluate, sample and give pdfs of a material exported in the runtime layout (`brdfz
// export IN -o OUT.brdfzrt`, formats/SPEC.md §6), with nothing but the C++17 standard library.
//
//   #include <brdfz/runtime/runtime.h>
//   std::string error;
//   const brdfz::runtime::Material m = brdfz::runtime::Material::open("paint.brdfzrt", &error);
//   if (!m) { /* error says why, in one line */ }
//   brdfz::runtime::Rgb32 f = m.eval(wi, wo);                   // f_r in 1/sr, no cosine
//   brdfz::runtime::Sample32 s = m.sample(wo, u1, u2);          // wi, pdf, weight = f·cosθi/pdf
//   float p = m.pdf(wo, s.wi);                                  // equals s.pdf
//
// Conventions are the library's (brdfz/brdf.h): local frame with the normal +z, wi and wo pointing away
// from the surface; below the horizon eval and pdf are 0 and a draw fails (pdf 0, weight 0). Directions
// need not be unit: one whose squared length is off 1 by more than 1e-14 is normalised; a NaN,
// infinite or zero one gives 0 and pdf 0. u outside [0, 1) gives a failed draw.
//
// The float32 calls take and return floats; the arithmetic is the library's, in double, so results
// are the library's to float rounding. No call allocates, throws or locks; a Material is immutable and
// may be shared by any number of threads. Copies share the data.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "brdfz/runtime/vec.h"

namespace brdfz::runtime {

struct Float3 {
    float x = 0, y = 0, z = 0;
};
struct Rgb32 {
    float r = 0, g = 0, b = 0;
};
struct Sample32 {
    Float3 wi;
    float pdf = 0;  // per unit solid angle of wi; 0: a failed draw
    Rgb32 weight;   // f(wi, wo)·cosθi / pdf
};
using Rgb64 = std::array<double, 3>;
struct Sample64 {
    Vec3 wi;
    double pdf = 0;
    Rgb64 weight{};
};

using brdfz::prepare_direction;  // vec.h: the rule every call applies to its directions

namespace detail {
struct Data;
// A material's calls, in the build for this CPU (brdfz/runtime/kernels/simd.h), picked when it is
// parsed; an empty material's give 0. They take prepared directions above the horizon, and u in [0, 1).
struct Calls {
    Rgb64 (*eval)(const Data*, const Vec3& wi, const Vec3& wo);
    double (*pdf)(const Data*, const Vec3& wo, const Vec3& wi);
    Sample64 (*sample)(const Data*, const Vec3& wo, double u1, double u2);
};
extern const Calls kNoCalls;
}  // namespace detail

class Material {
public:
    Material() = default;  // empty: every call gives 0

    // The material in a .brdfzrt file, mapped read-only; empty with *error set (one line) when the
    // file cannot be read or is not a valid runtime layout (every size and table is checked first).
    static Material open(const std::string& path, std::string* error = nullptr);
    // The same from bytes in memory: copied, or borrowed when `copy` is false (they must then outlive
    // every copy of the Material and stay unchanged).
    static Material from_memory(const void* data, std::size_t size, bool copy = true, std::string* error = nullptr);

    explicit operator bool() const { return d_ != nullptr; }
    // What the material is ("svd ... dtype f16"), as the library described it when it was exported.
    std::string describe() const;
    // The layout's bytes (the file), e.g. to upload them to a GPU, their size, and the size of the
    // sampler's sections among them.
    const void* data() const;
    std::size_t nbytes() const;
    std::size_t sampler_nbytes() const;

    // One call each, inline, as the library's Brdf: the directions are prepared here, in the caller,
    // and the call table's entry is the only indirection.
    Rgb32 eval(const Float3& wi, const Float3& wo) const noexcept {
        const Rgb64 f = eval(widen(wi), widen(wo));
        return {static_cast<float>(f[0]), static_cast<float>(f[1]), static_cast<float>(f[2])};
    }
    float pdf(const Float3& wo, const Float3& wi) const noexcept { return static_cast<float>(pdf(widen(wo), widen(wi))); }
    Sample32 sample(const Float3& wo, float u1, float u2) const noexcept {
        const Sample64 s = sample(widen(wo), u1, u2);
        return {{static_cast<float>(s.wi.x), static_cast<float>(s.wi.y), static_cast<float>(s.wi.z)},
                static_cast<float>(s.pdf),
                {static_cast<float>(s.weight[0]), static_cast<float>(s.weight[1]), static_cast<float>(s.weight[2])}};
    }

    Rgb64 eval(const Vec3& wi, const Vec3& wo) const noexcept {
        Vec3 a = wi, b = wo;
        if (!prepare_direction(a) || !prepare_direction(b) || !(a.z > 0.0 && b.z > 0.0)) return {0.0, 0.0, 0.0};
        return calls_->eval(d_.get(), a, b);
    }
    double pdf(const Vec3& wo, const Vec3& wi) const noexcept {
        Vec3 a = wo, b = wi;
        if (!prepare_direction(a) || !prepare_direction(b) || !(a.z > 0.0 && b.z > 0.0)) return 0.0;
        return calls_->pdf(d_.get(), a, b);
    }
    Sample64 sample(const Vec3& wo, double u1, double u2) const noexcept {
        Vec3 a = wo;
        if (!prepare_direction(a) || !(a.z > 0.0 && u1 >= 0.0 && u1 < 1.0 && u2 >= 0.0 && u2 < 1.0)) return {};
        return calls_->sample(d_.get(), a, u1, u2);
    }

    // Batches: out[k] for pair or draw k; u holds n (u1, u2) pairs.
    void eval(const Float3* wi, const Float3* wo, Rgb32* out, std::size_t n) const noexcept;
    void pdf(const Float3* wo, const Float3* wi, float* out, std::size_t n) const noexcept;
    void sample(const Float3* wo, const float* u, Sample32* out, std::size_t n) const noexcept;

private:
    explicit Material(std::shared_ptr<const detail::Data> d);
    static Vec3 widen(const Float3& v) { return {v.x, v.y, v.z}; }
    std::shared_ptr<const detail::Data> d_;
    const detail::Calls* calls_ = &detail::kNoCalls;
};

}  // namespace brdfz::runtime
