#include "brdfz/control.h"

#include <algorithm>
#include <string>
#include <thread>

#include "brdfz/errors.h"

namespace brdfz {
namespace {

thread_local const StopCheck* current = nullptr;

}  // namespace

int resolve_threads(int threads) {
    if (threads > kMaxThreads)
        throw ValueError("threads = " + std::to_string(threads) + " is above the limit of " +
                         std::to_string(kMaxThreads) + " (0: one per hardware thread)");
    if (threads > 0) return threads;
    return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

StopScope::StopScope(StopCheck check) : check_(std::move(check)), previous_(current) {
    if (check_) current = &check_;
}

StopScope::~StopScope() { current = previous_; }

void poll_stop() {
    if (current) (*current)();
}

namespace detail {

const StopCheck* current_stop() { return current; }

InheritedStop::InheritedStop(const StopCheck* check) : previous_(current) { current = check; }

InheritedStop::~InheritedStop() { current = previous_; }

}  // namespace detail
}  // namespace brdfz
