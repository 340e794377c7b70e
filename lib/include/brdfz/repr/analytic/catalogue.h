// Every lobe family a model string can name: the runtime's list (brdfz/runtime/kernels/lobes/
// families.h) as the core's catalogue. The runtime catalogue (lobe_types) and the fitting code's
// autodiff instantiations are both generated from it, in its order, so they cannot disagree with each
// other or with the runtime's family ids.
#pragma once

#include <array>
#include <span>
#include <string_view>

#include "brdfz/repr/analytic/lobe.h"
#include "brdfz/runtime/kernels/lobes/families.h"

namespace brdfz {

template <typename... Families>
struct LobeList {
    static constexpr std::size_t size = sizeof...(Families);
    static constexpr std::array<LobeType, size> types{lobe_type<Families>()...};
};

namespace detail {
template <typename... Families>
LobeList<Families...> lobe_list_of(lobes::FamilyList<Families...>);
}  // namespace detail

using AllLobes = decltype(detail::lobe_list_of(lobes::AllFamilies{}));

// The runtime catalogue, in AllLobes order.
inline std::span<const LobeType> lobe_types() { return AllLobes::types; }

// Position of a family in the catalogue (its runtime family id), or -1.
inline int find_lobe_type(std::string_view name) { return runtime::kernels::lobe_family(name); }

}  // namespace brdfz
