// How long operations run: the bound on their `threads` option, and how a caller stops them.
//
// Stopping: a caller that cannot rely on a signal's default action to end the work (Python, where
// Ctrl-C raises KeyboardInterrupt only once control is back in the interpreter) installs a check with
// a StopScope for the span of a call. The library calls poll_stop() between items of work: after
// every item of its parallel loops (tabulation, metrics, factorisation and fitting passes, PCA), after
// every solver iteration of a fit, between the runs of an eval-speed measurement and the candidates of
// a selection. A check that throws ends the operation with its exception, which passes through the
// library unchanged; it should not derive from brdfz::Error, which a selection catches to go on to
// the next candidate. Nothing is written by an operation that ends so: writers commit their output
// only once it is complete (formats/detail/atomic_file.h).
#pragma once

#include <functional>

namespace brdfz {

// The most threads an operation takes (its `threads` option, 0 or less: one per hardware thread).
inline constexpr int kMaxThreads = 1024;

// `threads` as operations take it: one per hardware thread for 0 or less, else `threads`; ValueError
// naming kMaxThreads above it.
int resolve_threads(int threads);

// Called by the library between items of work, from any of its threads (so it must be safe to call
// concurrently); it stops the operation by throwing.
using StopCheck = std::function<void()>;

// Installs `check` for the library's work on this thread and on the worker threads that work starts,
// until the scope ends; scopes nest (the inner one's check applies). An empty check installs none.
class StopScope {
public:
    explicit StopScope(StopCheck check);
    ~StopScope();
    StopScope(const StopScope&) = delete;
    StopScope& operator=(const StopScope&) = delete;

private:
    StopCheck check_;
    const StopCheck* previous_;
};

// Runs the check of the scope this thread works under, if any.
void poll_stop();

namespace detail {

// The check this thread works under (nullptr: none), for the library's worker threads to inherit
// with an InheritedStop.
const StopCheck* current_stop();

class InheritedStop {
public:
    explicit InheritedStop(const StopCheck* check);
    ~InheritedStop();
    InheritedStop(const InheritedStop&) = delete;
    InheritedStop& operator=(const InheritedStop&) = delete;

private:
    const StopCheck* previous_;
};

}  // namespace detail
}  // namespace brdfz
