// The sampler a gridded representation (tables, factorisations, PCA, φh stacks) draws from, chosen by
// the spec key sampler=:
//   compact  the default: a few kilobytes of fixed-point CDFs (sample/compact.h), stored with the
//            representation (a container holds them; older ones build them at load)
//   fine     the half-vector sampler (sample/halfvector.h): 1.6 MB of float CDFs on a fine grid
//   none     no sampler of its own (a φh stack's slices: the stack samples as a whole); sample() then
//            draws cosθi/π, as Brdf does for representations without a sampler
// Every sampler is built when the representation is, never on first use: a renderer's first sample()
// starts no thread and allocates nothing.
#pragma once

#include <memory>
#include <string>

#include "brdfz/brdf.h"
#include "brdfz/sample/compact.h"
#include "brdfz/sample/halfvector.h"

namespace brdfz {

enum class SamplerKind { Compact, Fine, None };
const char* sampler_kind_name(SamplerKind kind);          // "compact", "fine", "none"
SamplerKind parse_sampler_kind(const std::string& name);  // ValueError otherwise

class GridSampler {
public:
    GridSampler() = default;  // none
    explicit GridSampler(CompactSampler compact);
    // kind's sampler of `brdf`, built from its eval now.
    static GridSampler build(const Brdf& brdf, SamplerKind kind, const CompactSamplerOptions& options = {});

    SamplerKind kind() const;
    const CompactSampler* compact() const { return compact_.get(); }
    const HalfVectorSampler* fine() const { return fine_.get(); }

    // For wo above the horizon and u in [0, 1)²: wi and its pdf (0: failed), the weight unset.
    BrdfSample sample(const Vec3& wo, double u1, double u2) const;
    // Density of sample() at wi, for wo and wi above the horizon.
    double pdf(const Vec3& wo, const Vec3& wi) const;
    // Bytes of the sampler's tables.
    std::size_t nbytes() const;

private:
    std::unique_ptr<const CompactSampler> compact_;
    std::unique_ptr<const HalfVectorSampler> fine_;
};

}  // namespace brdfz
