// What every analytic lobe family shares: the geometry of a direction pair and parameter descriptions.
// The families (one header each beside this one, listed in families.h) are the one source of the
// lobes' arithmetic: the core evaluates, samples and fits with them (ceres::Jet through the same
// templates), brdfz::runtime evaluates and samples exported models with them.
//
// A family is a struct with
//   static constexpr std::string_view name;                 // its term in a model string, e.g. "ggx"
//   static constexpr std::array<ParamSpec, N> params;       // names, bounds, defaults, in storage order
//   static constexpr bool linear_weights;                   // f_c = p[c] · (f_c with p[0..2] = 1)?
//   template <typename T, typename S>
//   static void eval(const Geometry<S>& g, const T* p, T out[3]);   // f_r per channel, no cosine
//   static Vec3 sample(const double* p, const Vec3& wo, double u1, double u2);   // its sampler
//   static double pdf(const double* p, const Vec3& wo, const Vec3& w);           // sample()'s density
// T is the parameter/result scalar (double, float or ceres::Jet<double, N> for autodiff); S is the
// geometry scalar (double or float; Jets only ever see double geometry). eval is only called for
// pairs above the horizon but must stay finite for every such pair, grazing included, and is written
// without data-dependent branches (min/max/select) so batch loops vectorise.
// linear_weights declares that the first three parameters are colour weights scaling channel r, g, b
// and nothing else; fitting then differentiates the rest by autodiff and the weights in closed form.
// sample draws a direction on the whole unit sphere (possibly below the horizon) for wo above the
// horizon and u1, u2 in [0, 1), with a density that integrates to 1 there; pdf is that density at the
// unit vector w, per unit solid angle. The mixture (kernels/lobe_mixture.h) folds draws below the
// horizon back and weighs the lobes; sampling.h holds what the samplers share.
#pragma once

#include <cmath>
#include <limits>
#include <string_view>

#include "brdfz/runtime/kernels/math.h"

namespace brdfz {

// How a parameter behaves, for fitting: which starting values to draw and which bounds count as
// "hit" when a fit ends on them.
enum class ParamKind {
    Weight,    // a colour weight that scales a lobe; its lower bound 0 is a natural value (lobe absent)
    Linear,    // a shape parameter drawn uniformly between its bounds
    LogScale,  // a positive shape parameter spanning decades (roughness, exponent): drawn log-uniformly
};

struct ParamSpec {
    std::string_view name;
    double lo, hi;  // closed bounds; the lobe is energy-conserving (albedo <= 1) everywhere inside
    double init;    // default value, the first start of a fit
    ParamKind kind;
};

// Selection without a branch: both arms are computed, which lets loops over pairs vectorise and keeps
// Jets well defined (both arms must be finite).
template <typename T>
T select(bool condition, const T& a, const T& b) {
    return condition ? a : b;
}

// A direction pair in the local frame (brdf.h conventions) with its half vector h = (wi+wo)/|wi+wo|
// and d = wi·h = wo·h, the cosine Fresnel terms take.
template <typename S>
struct Geometry {
    S ix, iy, iz;  // wi
    S ox, oy, oz;  // wo
    S hx, hy, hz;  // h
    S d;           // wi·h, in [0, 1]
};

// Always inlined: batch loops over pairs only vectorise when no call is left in them.
template <typename S>
[[gnu::always_inline]] inline Geometry<S> make_geometry(S ix, S iy, S iz, S ox, S oy, S oz) {
    using std::sqrt;
    const S sx = ix + ox, sy = iy + oy, sz = iz + oz;
    // |wi + wo| vanishes only for opposite grazing pairs, which get h = ẑ as in vec.h's half_vector.
    const S n2 = sx * sx + sy * sy + sz * sz;
    const bool degenerate = !(n2 > std::numeric_limits<S>::min());
    const S inv = S(1) / sqrt(select(degenerate, std::numeric_limits<S>::min(), n2));
    Geometry<S> g{ix, iy, iz, ox, oy, oz, select(degenerate, S(0), sx * inv), select(degenerate, S(0), sy * inv),
                  select(degenerate, S(1), sz * inv), S(0)};
    // Clamped to [0, 1] by value selects (std::clamp's references leave branches in the loop).
    const S d = ix * g.hx + iy * g.hy + iz * g.hz;
    g.d = select(d > S(1), S(1), select(d > S(0), d, S(0)));
    return g;
}

// Numerical floor for denominators that vanish only at grazing angles, where the numerator vanishes
// faster (cosines, exp(-tan²)).
inline constexpr double kTiny = 1e-12;

namespace lobes {

// π and the double nearest 1/π (std::numbers is C++20; this is its inv_pi).
using runtime::kernels::kPi;
inline constexpr double kInvPi = 0.318309886183790671537767526745028724;

}  // namespace lobes

}  // namespace brdfz
