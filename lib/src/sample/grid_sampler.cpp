#include "brdfz/sample/grid_sampler.h"

#include <numbers>

#include "brdfz/errors.h"

namespace brdfz {

const char* sampler_kind_name(SamplerKind kind) {
    switch (kind) {
        case SamplerKind::Compact: return "compact";
        case SamplerKind::Fine: return "fine";
        default: return "none";
    }
}

SamplerKind parse_sampler_kind(const std::string& name) {
    if (name == "compact") return SamplerKind::Compact;
    if (name == "fine") return SamplerKind::Fine;
    if (name == "none") return SamplerKind::None;
    throw ValueError("unknown sampler '" + name + "' (expected compact, fine or none)");
}

GridSampler::GridSampler(CompactSampler compact) : compact_(std::make_unique<const CompactSampler>(std::move(compact))) {}

GridSampler GridSampler::build(const Brdf& brdf, SamplerKind kind, const CompactSamplerOptions& options) {
    GridSampler s;
    if (kind == SamplerKind::Compact) s.compact_ = std::make_unique<const CompactSampler>(brdf, options);
    if (kind == SamplerKind::Fine) {
        HalfVectorSamplerOptions fine;
        fine.threads = options.threads;
        s.fine_ = std::make_unique<const HalfVectorSampler>(brdf, fine);
    }
    return s;
}

SamplerKind GridSampler::kind() const {
    return compact_ ? SamplerKind::Compact : fine_ ? SamplerKind::Fine : SamplerKind::None;
}

BrdfSample GridSampler::sample(const Vec3& wo, double u1, double u2) const {
    if (compact_) return compact_->sample(wo, u1, u2);
    if (fine_) return fine_->sample(wo, u1, u2);
    const Vec3 wi = cosine_hemisphere(u1, u2);
    return {wi, wi.z / std::numbers::pi, {}};
}

double GridSampler::pdf(const Vec3& wo, const Vec3& wi) const {
    if (compact_) return compact_->pdf(wo, wi);
    if (fine_) return fine_->pdf(wo, wi);
    return wi.z / std::numbers::pi;
}

std::size_t GridSampler::nbytes() const { return compact_ ? compact_->nbytes() : fine_ ? fine_->nbytes() : 0; }

}  // namespace brdfz
