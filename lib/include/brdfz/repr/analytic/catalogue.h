// Every lobe family a model string can name, in one compile-time list. The runtime catalogue
// (lobe_types) and the fitting code's autodiff instantiations are both generated from it, in this
// order, so they cannot disagree.
#pragma once

#include <array>
#include <span>
#include <string_view>

#include "brdfz/repr/analytic/ashikhmin_shirley.h"
#include "brdfz/repr/analytic/blinn_phong.h"
#include "brdfz/repr/analytic/lafortune.h"
#include "brdfz/repr/analytic/lambert.h"
#include "brdfz/repr/analytic/lobe.h"
#include "brdfz/repr/analytic/microfacet.h"
#include "brdfz/repr/analytic/ward.h"

namespace brdfz {

template <typename... Families>
struct LobeList {
    static constexpr std::size_t size = sizeof...(Families);
    static constexpr std::array<LobeType, size> types{lobe_type<Families>()...};
};

using AllLobes = LobeList<lobes::Lambert, lobes::BlinnPhong, lobes::Ward, lobes::Ggx, lobes::GgxDielectric,
                          lobes::GgxConductor, lobes::GgxSep, lobes::GgxDielectricSep, lobes::GgxConductorSep,
                          lobes::Beckmann, lobes::BeckmannDielectric, lobes::BeckmannConductor, lobes::GgxAniso,
                          lobes::AshikhminShirley, lobes::Lafortune>;

// The runtime catalogue, in AllLobes order.
inline std::span<const LobeType> lobe_types() { return AllLobes::types; }

// Position of a family in the catalogue, or -1.
inline int find_lobe_type(std::string_view name) {
    for (std::size_t i = 0; i < AllLobes::size; ++i)
        if (AllLobes::types[i].name == name) return static_cast<int>(i);
    return -1;
}

}  // namespace brdfz
