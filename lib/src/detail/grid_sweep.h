// Visit a Rusinkiewicz grid one θh slice at a time, in parallel, with the direction pair at each bin's
// sample position (φh = 0: isotropic sources). Shared by tabulation and metrics.
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

// fn(worker, ih, wi, wo) for every θh slice ih; wi/wo hold the slice's n_theta_d·n_phi_d pairs in
// bin order. progress(done_slices, total) is called under a lock after each slice. The first exception
// thrown by fn stops the sweep and is rethrown here.
template <typename Fn>
void sweep_slices(const GridSpec& g, int threads, Fn&& fn,
                  const std::function<void(int, int)>& progress = nullptr) {
    const int workers = std::min(resolve_threads(threads), g.n_theta_h);
    std::atomic<int> next{0};
    std::atomic<bool> failed{false};
    std::exception_ptr error;
    std::mutex mutex;
    int done = 0;
    auto work = [&](int worker) {
        const std::size_t per_slice = static_cast<std::size_t>(g.n_theta_d) * g.n_phi_d;
        std::vector<Vec3> wi(per_slice), wo(per_slice);
        for (int ih; !failed && (ih = next++) < g.n_theta_h;) {
            try {
                const double theta_h = g.theta_h_at(ih);
                for (int id = 0; id < g.n_theta_d; ++id)
                    for (int ip = 0; ip < g.n_phi_d; ++ip) {
                        const std::size_t k = static_cast<std::size_t>(id) * g.n_phi_d + ip;
                        std::tie(wi[k], wo[k]) = from_half_diff({theta_h, 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
                    }
                fn(worker, ih, std::span<const Vec3>(wi), std::span<const Vec3>(wo));
                std::lock_guard lock(mutex);
                ++done;
                if (progress) progress(done, g.n_theta_h);
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

}  // namespace brdfz::detail
