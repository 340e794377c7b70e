// The library's one parallel loop: every multi-threaded pass (tabulation, metrics, fitting,
// factorisation, PCA, sampler builds) runs through it, so threads, progress and errors behave alike.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "brdfz/control.h"

namespace brdfz::detail {

// fn(worker, i) for i in [0, n) on up to `threads` workers (worker < threads; resolve_threads,
// control.h), each taking the next unclaimed i. After each item the caller's stop check runs (on every
// worker: they inherit it) and then progress(done, n), under a lock. The first exception thrown by fn,
// the check or progress stops the loop and is rethrown.
template <typename Fn>
void parallel_for(int n, int threads, Fn&& fn, const std::function<void(int, int)>& progress = nullptr) {
    const int workers = std::max(1, std::min(resolve_threads(threads), n));
    std::atomic<int> next{0};
    std::atomic<bool> failed{false};
    std::exception_ptr error;
    std::mutex mutex;
    int done = 0;
    const StopCheck* stop = current_stop();
    auto work = [&](int worker) {
        const InheritedStop inherited(stop);
        for (int i; !failed && (i = next++) < n;) {
            try {
                fn(worker, i);
                poll_stop();
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

}  // namespace brdfz::detail
