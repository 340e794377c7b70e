// Every lobe family a model string can name, in one list, and the family kernels by position in it
// (the family id). The core's catalogue (repr/analytic/catalogue.h: AllLobes, lobe_types()) is
// generated from this list in this order, so a family's id is the same in the library, in
// brdfz::runtime and in an exported model.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

#include "brdfz/runtime/kernels/lobes/ashikhmin_shirley.h"
#include "brdfz/runtime/kernels/lobes/blinn_phong.h"
#include "brdfz/runtime/kernels/lobes/lafortune.h"
#include "brdfz/runtime/kernels/lobes/lambert.h"
#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/microfacet.h"
#include "brdfz/runtime/kernels/lobes/ward.h"
#include "brdfz/runtime/vec.h"

namespace brdfz::lobes {

template <typename... Families>
struct FamilyList {
    static constexpr std::size_t size = sizeof...(Families);
};

using AllFamilies = FamilyList<Lambert, BlinnPhong, Ward, Ggx, GgxDielectric, GgxConductor, GgxSep, GgxDielectricSep,
                               GgxConductorSep, Beckmann, BeckmannDielectric, BeckmannConductor, GgxAniso,
                               AshikhminShirley, Lafortune>;

// Family F's density folded onto the upper hemisphere: the mixture keeps a draw below the horizon by
// mirroring it in z, so the density at wi is F's at wi and at wi mirrored.
template <typename F>
[[gnu::always_inline]] inline double folded_pdf(const double* p, const Vec3& wo, const Vec3& wi) {
    return F::pdf(p, wo, wi) + F::pdf(p, wo, {wi.x, wi.y, -wi.z});
}

}  // namespace brdfz::lobes

namespace brdfz::runtime::kernels {

// A family's kernels for double parameters, as lobe.h describes them.
struct LobeFamily {
    std::string_view name;  // its term in a model string
    std::size_t params;     // how many parameters it reads
    const ParamSpec* specs; // theirs, with the bounds inside which the lobe is valid
    void (*eval)(const Geometry<double>& g, const double* p, double out[3]);
    Vec3 (*sample)(const double* p, const Vec3& wo, double u1, double u2);
    double (*pdf)(const double* p, const Vec3& wo, const Vec3& w);
    double (*folded_pdf)(const double* p, const Vec3& wo, const Vec3& wi);
};

template <typename... Families>
constexpr std::array<LobeFamily, sizeof...(Families)> lobe_families_of(lobes::FamilyList<Families...>) {
    return {LobeFamily{Families::name, Families::params.size(), Families::params.data(),
                       &Families::template eval<double, double>,
                       &Families::sample, &Families::pdf, &lobes::folded_pdf<Families>}...};
}

// Every family, indexed by its id.
inline constexpr std::array<LobeFamily, lobes::AllFamilies::size> kLobeFamilies =
    lobe_families_of(lobes::AllFamilies{});

// The id of the family a model string's term names ("ggx", without a repeat count), or -1.
inline int lobe_family(std::string_view name) {
    for (std::size_t i = 0; i < kLobeFamilies.size(); ++i)
        if (kLobeFamilies[i].name == name) return static_cast<int>(i);
    return -1;
}

}  // namespace brdfz::runtime::kernels
