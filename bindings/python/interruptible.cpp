#include <atomic>
#include <mutex>
#include <thread>

#include "module.h"

namespace brdfz::python {

struct Interruptible::State {
    py::object callable;
    std::mutex progress_mutex;  // one progress call at a time
    std::mutex error_mutex;
    std::exception_ptr error;  // what stopped the work: the first exception only
    std::atomic<bool> stopped{false};
    std::thread::id caller = std::this_thread::get_id();
    std::chrono::steady_clock::time_point next_poll{};  // read and written on the caller's thread only

    // Keeps the first exception and stops the work.
    [[noreturn]] void fail(std::exception_ptr e) {
        {
            std::lock_guard lock(error_mutex);
            if (!error) error = std::move(e);
        }
        stopped = true;
        throw Stopped{};
    }
};

Interruptible::Interruptible(py::object progress) : state_(std::make_shared<State>()) {
    if (!progress.is_none()) state_->callable = std::move(progress);
}

std::function<void(double)> Interruptible::progress() {
    if (!state_->callable) return nullptr;
    return [state = state_](double fraction) {
        if (state->stopped) throw Stopped{};
        std::lock_guard lock(state->progress_mutex);
        py::gil_scoped_acquire gil;
        try {
            state->callable(fraction);
        } catch (py::error_already_set&) {
            state->fail(std::current_exception());
        }
    };
}

void Interruptible::call(const std::function<void()>& fn) {
    if (state_->stopped) throw Stopped{};
    py::gil_scoped_acquire gil;
    try {
        fn();
    } catch (py::error_already_set&) {
        state_->fail(std::current_exception());
    }
}

StopCheck Interruptible::stop_check() {
    return [state = state_] {
        if (state->stopped) throw Stopped{};
        if (std::this_thread::get_id() != state->caller) return;
        const auto now = std::chrono::steady_clock::now();
        if (now < state->next_poll) return;
        state->next_poll = now + kSignalPoll;
        py::gil_scoped_acquire gil;
        // Runs the handlers of the signals that arrived (on Python's main thread; elsewhere it does
        // nothing): Ctrl-C's raises KeyboardInterrupt.
        if (PyErr_CheckSignals() != 0) state->fail(std::make_exception_ptr(py::error_already_set()));
    };
}

void Interruptible::raise() {
    std::exception_ptr error;
    {
        std::lock_guard lock(state_->error_mutex);
        error = state_->error;
    }
    std::rethrow_exception(error);
}

}  // namespace brdfz::python
