#include "brdfz/repr/tabular.h"

#include <cmath>
#include <memory>

#include "brdfz/coords.h"
#include "brdfz/errors.h"

namespace brdfz {
namespace {

// Continuous bin coordinates (θh, θd, φd) of a direction pair on a grid.
struct BinCoords {
    double uh, ud, up;
};

inline BinCoords bin_coords(const GridSpec& g, const Vec3& wi, const Vec3& wo) {
    const Vec3 h = half_vector(wi, wo);
    const Vec3 d = difference_vector(wi, half_frame(h));
    return {axis::theta_h_to_u(elevation(h), g.n_theta_h), axis::theta_d_to_u(elevation(d), g.n_theta_d),
            axis::phi_d_to_u(std::atan2(d.y, d.x), g.n_phi_d)};
}

inline Rgb lookup_nearest(const Table& t, const Vec3& wi, const Vec3& wo) {
    const GridSpec& g = t.grid();
    const BinCoords c = bin_coords(g, wi, wo);
    const float* v = t.data() + 3 * g.index(axis::bin_of(c.uh, g.n_theta_h), axis::bin_of(c.ud, g.n_theta_d),
                                            axis::bin_of(c.up, g.n_phi_d));
    Rgb f;
    for (int ch = 0; ch < 3; ++ch) f[ch] = std::isnan(v[ch]) ? 0.0 : v[ch];
    return f;
}

// Two neighbouring samples along a clamped axis and the weight of the second.
struct Span {
    int i0, i1;
    double t;
};

inline Span clamped_span(double c, int n) {
    c = std::fmin(std::fmax(c, 0.0), n - 1.0);  // also maps NaN to 0
    const int i0 = static_cast<int>(c);
    const int i1 = i0 + 1 < n ? i0 + 1 : i0;
    return {i0, i1, c - i0};
}

inline Span periodic_span(double c, int n) {
    c = std::fmod(c, static_cast<double>(n));
    if (c < 0.0) c += n;
    if (!(c < n)) c = 0.0;  // c == n after rounding, or NaN
    const int i0 = static_cast<int>(c);
    return {i0, i0 + 1 < n ? i0 + 1 : 0, c - i0};
}

inline Rgb lookup_linear(const Table& t, const Vec3& wi, const Vec3& wo) {
    const GridSpec& g = t.grid();
    const BinCoords c = bin_coords(g, wi, wo);
    const double off = g.sample_offset();
    const Span sh = clamped_span(c.uh - off, g.n_theta_h);
    const Span sd = clamped_span(c.ud - off, g.n_theta_d);
    const Span sp = periodic_span(c.up - off, g.n_phi_d);

    double sum[3] = {0, 0, 0}, wsum[3] = {0, 0, 0};
    for (int a = 0; a < 2; ++a) {
        const int ih = a ? sh.i1 : sh.i0;
        const double wa = a ? sh.t : 1.0 - sh.t;
        for (int b = 0; b < 2; ++b) {
            const int id = b ? sd.i1 : sd.i0;
            const double wb = wa * (b ? sd.t : 1.0 - sd.t);
            for (int p = 0; p < 2; ++p) {
                const double w = wb * (p ? sp.t : 1.0 - sp.t);
                const float* v = t.data() + 3 * g.index(ih, id, p ? sp.i1 : sp.i0);
                for (int ch = 0; ch < 3; ++ch) {
                    // Invalid samples are NaN: they contribute neither value nor weight.
                    const bool ok = v[ch] == v[ch];
                    sum[ch] += ok ? w * v[ch] : 0.0;
                    wsum[ch] += ok ? w : 0.0;
                }
            }
        }
    }
    Rgb f;
    for (int ch = 0; ch < 3; ++ch) f[ch] = wsum[ch] > 0.0 ? sum[ch] / wsum[ch] : 0.0;
    return f;
}

}  // namespace

Lookup parse_lookup(const std::string& name) {
    if (name == "nearest") return Lookup::Nearest;
    if (name == "linear") return Lookup::Linear;
    throw ValueError("unknown lookup '" + name + "' (expected nearest or linear)");
}

const char* lookup_name(Lookup lookup) { return lookup == Lookup::Nearest ? "nearest" : "linear"; }

TabularBrdf::TabularBrdf(Table table, Lookup lookup) : table_(std::move(table)), lookup_(lookup) {}

std::string TabularBrdf::describe() const {
    return "tabular " + table_.grid().str() + " float32, bin " +
           (table_.grid().position == BinPosition::Start ? "start" : "centre") + ", " + lookup_name(lookup_) +
           " lookup";
}

Rgb TabularBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    return lookup_ == Lookup::Nearest ? lookup_nearest(table_, wi, wo) : lookup_linear(table_, wi, wo);
}

void TabularBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    const Rgb zero{0.0, 0.0, 0.0};
    if (lookup_ == Lookup::Nearest) {
        for (std::size_t k = 0; k < n; ++k)
            out[k] = wi[k].z > 0.0 && wo[k].z > 0.0 ? lookup_nearest(table_, wi[k], wo[k]) : zero;
    } else {
        for (std::size_t k = 0; k < n; ++k)
            out[k] = wi[k].z > 0.0 && wo[k].z > 0.0 ? lookup_linear(table_, wi[k], wo[k]) : zero;
    }
}

const HalfVectorSampler& TabularBrdf::sampler() const {
    return sampler_.get([this] { return std::make_unique<HalfVectorSampler>(*this); });
}

BrdfSample TabularBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    return sampler().sample(wo, u1, u2);
}

double TabularBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return sampler().pdf(wo, wi); }

}  // namespace brdfz
