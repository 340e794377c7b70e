// A sweep of a Rusinkiewicz grid one θh slice at a time, in parallel (detail/parallel.h), with the
// direction pair at each bin's sample position (φh = 0: isotropic sources).
#pragma once

#include <algorithm>
#include <functional>
#include <span>
#include <tuple>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/table.h"
#include "detail/parallel.h"

namespace brdfz::detail {

// fn(worker, ih, wi, wo) for every θh slice ih; wi/wo hold the slice's n_theta_d·n_phi_d pairs in
// bin order.
template <typename Fn>
void sweep_slices(const GridSpec& g, int threads, Fn&& fn,
                  const std::function<void(int, int)>& progress = nullptr) {
    const int workers = std::max(1, std::min(resolve_threads(threads), g.n_theta_h));
    const std::size_t per_slice = static_cast<std::size_t>(g.n_theta_d) * g.n_phi_d;
    std::vector<std::vector<Vec3>> wi(workers, std::vector<Vec3>(per_slice)), wo = wi;
    parallel_for(
        g.n_theta_h, workers,
        [&](int w, int ih) {
            const double theta_h = g.theta_h_at(ih);
            for (int id = 0; id < g.n_theta_d; ++id)
                for (int ip = 0; ip < g.n_phi_d; ++ip) {
                    const std::size_t k = static_cast<std::size_t>(id) * g.n_phi_d + ip;
                    std::tie(wi[w][k], wo[w][k]) = from_half_diff({theta_h, 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                }
            fn(w, ih, std::span<const Vec3>(wi[w]), std::span<const Vec3>(wo[w]));
        },
        progress);
}

}  // namespace brdfz::detail
