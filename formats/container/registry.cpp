#include "storage.h"

namespace brdfz::container {
namespace detail {

std::span<const StorageModule* const> storage_modules() {
    static const StorageModule* const kModules[] = {&tabular_storage(), &rgl_storage(), &analytic_storage(),
                                                    &pca_storage(), &factored_storage(), &phi_h_storage()};
    return kModules;
}

const StorageModule* find_storage(std::string_view type) {
    for (const StorageModule* m : storage_modules())
        if (m->type == type) return m;
    return nullptr;
}

}  // namespace detail

std::vector<Feature> known_features() {
    std::vector<Feature> out{detail::kCore};
    for (const detail::StorageModule* m : detail::storage_modules())
        out.insert(out.end(), m->features.begin(), m->features.end());
    return out;
}

}  // namespace brdfz::container
