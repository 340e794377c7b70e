#include <mutex>

#include "module.h"

namespace brdfz::python {

struct Progress::State {
    py::object callable;
    std::mutex mutex;
    std::exception_ptr error;
};

Progress::Progress(py::object callable) : state_(std::make_shared<State>()) {
    if (!callable.is_none()) state_->callable = std::move(callable);
}

std::function<void(double)> Progress::hook() {
    if (!state_->callable) return nullptr;
    return [state = state_](double fraction) {
        std::lock_guard lock(state->mutex);
        if (state->error) return;  // stop calling a callable that failed
        py::gil_scoped_acquire gil;
        try {
            state->callable(fraction);
        } catch (py::error_already_set&) {
            state->error = std::current_exception();
        }
    };
}

void Progress::rethrow() {
    if (state_->error) std::rethrow_exception(state_->error);
}

}  // namespace brdfz::python
