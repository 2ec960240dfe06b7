#pragma once
// Long calls of the Python module: the GIL released, and Ctrl-C honoured.
#include <pybind11/pybind11.h>

#include <chrono>
#include <future>
#include <type_traits>
#include <utility>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/progress.hpp"

namespace coarsegrain::python {

using coarsegrain::Interrupted;

/// Runs f() on a worker thread while the calling thread, the GIL released, waits for it and every
/// 50 ms lets Python handle pending signals (PyErr_CheckSignals, which only the main thread
/// does). If a handler raises (Ctrl-C: KeyboardInterrupt), the computation is asked to stop at
/// its next phase boundary (request_interrupt: Phase throws Interrupted), and once it has stopped
/// (or finished) that Python exception is raised. f's own exceptions propagate. f must not touch
/// Python objects. Returns f's result.
template <class F>
auto run_interruptible(F&& f) -> decltype(f()) {
    using R = decltype(f());
    std::future<R> done = std::async(std::launch::async, std::forward<F>(f));
    {
        pybind11::gil_scoped_release release;
        while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
            bool raised = false;
            {
                pybind11::gil_scoped_acquire acquire;
                raised = PyErr_CheckSignals() != 0;
            }
            if (raised) {
                request_interrupt();
                done.wait();
                clear_interrupt();
                pybind11::gil_scoped_acquire acquire;
                throw pybind11::error_already_set();
            }
        }
    }
    return done.get();
}

}  // namespace coarsegrain::python
