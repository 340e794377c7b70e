// A value built on first use, once, safely from several threads: representations keep their samplers
// in one so that loading stays fast and eval-only users never pay for sampling tables. Copies and
// moves start empty (the copy builds its own on demand).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>

namespace brdfz {

template <typename T>
class Lazy {
public:
    Lazy() = default;
    Lazy(const Lazy&) {}
    Lazy& operator=(const Lazy&) {
        reset();
        return *this;
    }

    template <typename Make>
    const T& get(Make&& make) const {
        if (const T* p = ptr_.load(std::memory_order_acquire)) return *p;
        std::lock_guard lock(mutex_);
        if (!owner_) {
            owner_ = make();
            ptr_.store(owner_.get(), std::memory_order_release);
        }
        return *owner_;
    }

    // Not thread-safe against concurrent get(): for use by the owner while it changes state.
    void reset() {
        std::lock_guard lock(mutex_);
        ptr_.store(nullptr, std::memory_order_release);
        owner_.reset();
    }

private:
    mutable std::mutex mutex_;
    mutable std::atomic<const T*> ptr_{nullptr};
    mutable std::unique_ptr<const T> owner_;
};

}  // namespace brdfz
