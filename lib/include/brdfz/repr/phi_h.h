// A φh axis for tables: anisotropic data as a stack of nφh isotropic-layout tables, one per half-vector
// azimuth φh (the azimuth of h = normalize(wi + wo) about the normal, from the tangent +x).
//
// Slice k holds the source at φh = φk: it is any Brdf built from the source rotated about the normal
// by φk (so that the pairs it tabulates at φh = 0 are the source's pairs at φk), on the usual
// (θh, θd, φd) grid. eval(wi, wo) reads the two slices around the pair's φh at (wi, wo) itself — their
// lookups ignore φh — and interpolates linearly in φh. Symmetries (spec key `symmetry`):
//   none        φh over [0, 2π), nφh slices at φk = (k + ½)·2π/nφh, periodic; slices keep φd over [0, 2π).
//   reciprocal  as none along φh (exchanging wi and wo keeps h, so φh is unchanged); slices fold φd by
//               reciprocity (φd ~ φd + π), as isotropic tables do.
//   bilateral   mirror symmetry about the tangent +x (y → −y), (φh, φd) ~ (−φh, −φd): φh over [0, π],
//               slices at φk = (k + ½)·π/nφh; a pair with φh < 0 is read mirrored. The interpolation is
//               clamped at 0 and π, where the mirror makes f symmetric in φh. Slices keep φd over [0, 2π).
// Sampling (sample/grid_sampler.h): by default one compact sampler of the whole stack, built from its
// eval averaged over view azimuths (the slices then carry no sampler of their own); with sampler=fine
// an even mixture of the slices' own fine samplers (each draws over every φh), so the pdf is the mean
// of their pdfs. Either pdf is exact; weights use the interpolated f.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/sample/grid_sampler.h"
#include "brdfz/table.h"

namespace brdfz {

enum class PhiHSymmetry { None, Reciprocal, Bilateral };
const char* phi_h_symmetry_name(PhiHSymmetry s);            // "none", "reciprocal", "bilateral"
PhiHSymmetry parse_phi_h_symmetry(const std::string& name);  // ValueError otherwise
// The φd symmetry of the slices: Reciprocal for reciprocal, None otherwise.
Symmetry slice_symmetry(PhiHSymmetry s);

class PhiHBrdf final : public Brdf {
public:
    // The most slices a spec's phih= asks for: what one .brdfz container stores. Its header lists at
    // most kMaxStoredDatasets datasets (formats/SPEC.md §1): the stack's compact sampler takes four, a
    // table slice one, a factored slice two (u, v), three with colour=shared.
    static constexpr int kMaxStoredDatasets = 253;
    static constexpr int kSamplerDatasets = 4;
    static constexpr int kMaxTableSlices = kMaxStoredDatasets - kSamplerDatasets;
    static constexpr int kMaxFactoredSlices = (kMaxStoredDatasets - kSamplerDatasets) / 3;

    // ValueError unless there are 2..GridSpec::kMaxAxis slices, all non-null with the same channels.
    // sampler: Compact builds the stack's own sampler now; Fine samples the slices' own samplers; None
    // draws cosθi/π.
    PhiHBrdf(std::vector<std::unique_ptr<Brdf>> slices, PhiHSymmetry symmetry,
             SamplerKind sampler = SamplerKind::Compact);
    // With a stored compact sampler (a container's).
    PhiHBrdf(std::vector<std::unique_ptr<Brdf>> slices, PhiHSymmetry symmetry, CompactSampler sampler);

    // View azimuths the compact sampler's integrand is averaged over (the stack is anisotropic).
    static constexpr int kSamplerAzimuths = 4;

    // φh of slice k of n (radians).
    static double phi_at(int k, int n, PhiHSymmetry symmetry);

    const std::vector<std::unique_ptr<Brdf>>& slices() const { return slices_; }
    PhiHSymmetry symmetry() const { return symmetry_; }
    SamplerKind sampler_kind() const { return sampler_kind_; }
    // The stack's own sampler (compact), or none when it samples its slices' (fine) or draws cosθi/π.
    const GridSampler& sampler() const { return sampler_; }

    int channels() const override { return slices_.front()->channels(); }
    std::size_t nbytes() const override;
    std::string describe() const override;
    double measured_theta_max() const override { return slices_.front()->measured_theta_max(); }
    bool reciprocal() const override { return symmetry_ == PhiHSymmetry::Reciprocal; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override;
    double pdf_above(const Vec3& wo, const Vec3& wi) const override;

private:
    std::vector<std::unique_ptr<Brdf>> slices_;
    PhiHSymmetry symmetry_;
    SamplerKind sampler_kind_;
    GridSampler sampler_;
};

// `source` rotated about the normal by φ: f(wi, wo) = source.f(Rz(φ)·wi, Rz(φ)·wo). Borrows `source`.
class RotatedBrdf final : public Brdf {
public:
    RotatedBrdf(const Brdf& source, double phi);
    int channels() const override { return source_.channels(); }
    std::size_t nbytes() const override { return source_.nbytes(); }
    std::string describe() const override;
    double measured_theta_max() const override { return source_.measured_theta_max(); }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;

private:
    Vec3 rotate(const Vec3& v) const { return {c_ * v.x - s_ * v.y, s_ * v.x + c_ * v.y, v.z}; }
    const Brdf& source_;
    double phi_, c_, s_;
};

// The stack of n slices of `source`, slice k built by build(source rotated by phi_at(k)), sampled by
// `sampler` (the slices are to carry none for Compact, their fine ones for Fine); ValueError for n
// outside 2..GridSpec::kMaxAxis.
std::unique_ptr<PhiHBrdf> tabulate_phi_h(const Brdf& source, int n, PhiHSymmetry symmetry,
                                         const std::function<std::unique_ptr<Brdf>(const Brdf&)>& build,
                                         SamplerKind sampler = SamplerKind::Compact);

}  // namespace brdfz
