#include "brdfz/repr/phi_h.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "brdfz/errors.h"
#include "brdfz/runtime/kernels/phi_h.h"

namespace brdfz {
namespace {

constexpr double kPi = std::numbers::pi;

double phi_range(PhiHSymmetry s) { return s == PhiHSymmetry::Bilateral ? kPi : 2.0 * kPi; }

}  // namespace

const char* phi_h_symmetry_name(PhiHSymmetry s) {
    switch (s) {
        case PhiHSymmetry::None: return "none";
        case PhiHSymmetry::Reciprocal: return "reciprocal";
        case PhiHSymmetry::Bilateral: return "bilateral";
    }
    return "none";
}

PhiHSymmetry parse_phi_h_symmetry(const std::string& name) {
    if (name == "none") return PhiHSymmetry::None;
    if (name == "reciprocal") return PhiHSymmetry::Reciprocal;
    if (name == "bilateral") return PhiHSymmetry::Bilateral;
    throw ValueError("symmetry must be none, reciprocal or bilateral, not '" + name + "'");
}

Symmetry slice_symmetry(PhiHSymmetry s) { return s == PhiHSymmetry::Reciprocal ? Symmetry::Reciprocal : Symmetry::None; }

double PhiHBrdf::phi_at(int k, int n, PhiHSymmetry symmetry) { return (k + 0.5) * phi_range(symmetry) / n; }

PhiHBrdf::PhiHBrdf(std::vector<std::unique_ptr<Brdf>> slices, PhiHSymmetry symmetry, SamplerKind sampler)
    : slices_(std::move(slices)), symmetry_(symmetry), sampler_kind_(sampler) {
    if (slices_.size() < 2 || slices_.size() > static_cast<std::size_t>(GridSpec::kMaxAxis))
        throw ValueError("phih: " + std::to_string(slices_.size()) + " slices, expected 2.." +
                         std::to_string(GridSpec::kMaxAxis));
    for (const auto& s : slices_)
        if (!s || s->channels() != slices_.front()->channels())
            throw ValueError("phih: slices must all be set and have the same channels");
    if (sampler == SamplerKind::Compact) {
        CompactSamplerOptions options;
        options.view_azimuths = kSamplerAzimuths;
        sampler_ = GridSampler::build(*this, SamplerKind::Compact, options);
    }
}

PhiHBrdf::PhiHBrdf(std::vector<std::unique_ptr<Brdf>> slices, PhiHSymmetry symmetry, CompactSampler sampler)
    : PhiHBrdf(std::move(slices), symmetry, SamplerKind::None) {
    sampler_kind_ = SamplerKind::Compact;
    sampler_ = GridSampler(std::move(sampler));
}

std::size_t PhiHBrdf::nbytes() const {
    std::size_t n = 0;
    for (const auto& s : slices_) n += s->nbytes();
    return n;
}

std::string PhiHBrdf::describe() const {
    return std::to_string(slices_.size()) + " φh slices (symmetry " + phi_h_symmetry_name(symmetry_) + ") of " +
           slices_.front()->describe();
}

Rgb PhiHBrdf::eval_above(const Vec3& wi_, const Vec3& wo_) const {
    const runtime::kernels::PhiHPick pick =
        runtime::kernels::phi_h_pick(symmetry_ == PhiHSymmetry::Bilateral, slices_.size(), wi_, wo_);
    if (!pick.ok) return {0.0, 0.0, 0.0};
    Vec3 wi = wi_, wo = wo_;
    if (pick.mirrored) wi.y = -wi.y, wo.y = -wo.y;
    const Rgb a = slices_[pick.k0]->eval(wi, wo), b = slices_[pick.k1]->eval(wi, wo);
    Rgb f;
    for (int c = 0; c < 3; ++c) f[c] = a[c] * (1.0 - pick.t) + b[c] * pick.t;
    return f;
}

BrdfSample PhiHBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    if (sampler_kind_ != SamplerKind::Fine) return sampler_.sample(wo, u1, u2);
    const std::size_t n = slices_.size();
    const double x = std::fmin(std::fmax(u1, 0.0), 1.0) * static_cast<double>(n);
    const std::size_t k = std::min(static_cast<std::size_t>(x), n - 1);
    const BrdfSample s = slices_[k]->sample(wo, std::fmin(x - static_cast<double>(k), 1.0), u2);
    if (!(s.pdf > 0.0)) return {};
    const double pdf = pdf_above(wo, s.wi);
    return {s.wi, pdf, {}};
}

double PhiHBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const {
    if (sampler_kind_ != SamplerKind::Fine) return sampler_.pdf(wo, wi);
    double sum = 0.0;
    for (const auto& s : slices_) sum += s->pdf(wo, wi);
    return sum / static_cast<double>(slices_.size());
}

RotatedBrdf::RotatedBrdf(const Brdf& source, double phi)
    : source_(source), phi_(phi), c_(std::cos(phi)), s_(std::sin(phi)) {}

std::string RotatedBrdf::describe() const {
    return source_.describe() + " rotated by " + std::to_string(phi_) + " rad about the normal";
}

Rgb RotatedBrdf::eval_above(const Vec3& wi, const Vec3& wo) const { return source_.eval(rotate(wi), rotate(wo)); }

void RotatedBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    std::vector<Vec3> a(n), b(n);
    for (std::size_t k = 0; k < n; ++k) {
        a[k] = rotate(wi[k]);
        b[k] = rotate(wo[k]);
    }
    std::vector<Rgb> f(n);
    source_.eval(a, b, f);
    for (std::size_t k = 0; k < n; ++k) out[k] = f[k];
}

std::unique_ptr<PhiHBrdf> tabulate_phi_h(const Brdf& source, int n, PhiHSymmetry symmetry,
                                         const std::function<std::unique_ptr<Brdf>(const Brdf&)>& build,
                                         SamplerKind sampler) {
    if (n < 2 || n > GridSpec::kMaxAxis)
        throw ValueError("phih=" + std::to_string(n) + " is outside 2.." + std::to_string(GridSpec::kMaxAxis));
    std::vector<std::unique_ptr<Brdf>> slices;
    for (int k = 0; k < n; ++k) slices.push_back(build(RotatedBrdf(source, PhiHBrdf::phi_at(k, n, symmetry))));
    return std::make_unique<PhiHBrdf>(std::move(slices), symmetry, sampler);
}

}  // namespace brdfz
