// Python's signal handlers while a run is in the core with the GIL released (Ctrl-C in a terminal, "interrupt
// kernel" in a notebook). Python runs them only in its main thread; elsewhere the poll answers false.
#pragma once
#include <pybind11/pybind11.h>

#include "granuflow/interrupt.hpp"

namespace granuflow::python {

// For the scope of a call into the core: at most every 0.1 s the GIL is taken and the handlers run. The default SIGINT
// handler raises KeyboardInterrupt; the run then ends with Interrupted, and the module's translator leaves Python's
// KeyboardInterrupt standing (module.cpp).
inline InterruptScope python_signals() {
  return InterruptScope([] {
    pybind11::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  });
}

// A call into the core from Python: Python's signal handlers polled (python_signals), the GIL released. Members in
// this order: the scope is installed while the GIL is still held, and outlives the release.
struct CoreCall {
  InterruptScope interrupt = python_signals();
  pybind11::gil_scoped_release release;
};

}  // namespace granuflow::python
