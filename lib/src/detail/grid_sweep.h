// Parallel loops shared by tabulation, metrics and samplers: a work-stealing loop over items, and a
// sweep of a Rusinkiewicz grid one θh slice at a time with the direction pair at each bin's sample
// position (φh = 0: isotropic sources).
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/table.h"

namespace brdfz::detail {

inline int resolve_threads(int threads) {
    if (threads > 0) return threads;
    return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// fn(worker, i) for i in [0, n) on up to `threads` workers (worker < threads). progress(done, n) is
// called under a lock after each item. The first exception thrown by fn stops the loop and is rethrown.
template <typename Fn>
void parallel_for(int n, int threads, Fn&& fn, const std::function<void(int, int)>& progress = nullptr) {
    const int workers = std::max(1, std::min(resolve_threads(threads), n));
    std::atomic<int> next{0};
    std::atomic<bool> failed{false};
    std::exception_ptr error;
    std::mutex mutex;
    int done = 0;
    auto work = [&](int worker) {
        for (int i; !failed && (i = next++) < n;) {
            try {
                fn(worker, i);
                std::lock_guard lock(mutex);
                ++done;
                if (progress) progress(done, n);
            } catch (...) {
                std::lock_guard lock(mutex);
                if (!error) error = std::current_exception();
                failed = true;
            }
        }
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(work, w);
    work(0);
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

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
