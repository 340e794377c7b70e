#include "storage.h"

#include <algorithm>

namespace brdfz::container {
namespace detail {

// Generated from container/storage/*.cpp (cmake/registry.cmake).
void register_all(std::vector<const StorageModule*>& out);

std::span<const StorageModule* const> storage_modules() {
    static const std::vector<const StorageModule*> modules = [] {
        std::vector<const StorageModule*> out;
        register_all(out);
        std::sort(out.begin(), out.end(), [](const StorageModule* a, const StorageModule* b) { return a->type < b->type; });
        return out;
    }();
    return modules;
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
