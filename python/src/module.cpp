// granuflow._core: the private compiled core. The public API is the pure-Python package granuflow.
#include <pybind11/pybind11.h>

#include <string>
#include <thread>

#include "allocator.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "granuflow/quantity.hpp"

namespace py = pybind11;

namespace granuflow::python {
void register_flowsheet(py::module_& m);
void register_kernels(py::module_& m);
void register_reference(py::module_& m);
void register_measured_psd(py::module_& m);
void register_montecarlo(py::module_& m);
void register_plugins(py::module_& m);
void register_files(py::module_& m);
void register_sweep_batch(py::module_& m);
void register_result(py::module_& m);
}  // namespace granuflow::python

PYBIND11_MODULE(_core, m) {
  m.doc() = "granuflow compiled core (use the granuflow package)";
  if (const std::string w = granuflow::python::tune_allocator(); !w.empty())
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) < 0) throw py::error_already_set();
  // ConfigError -> ValueError subclass; SolverError -> RuntimeError subclass with t, unit, worst_residual.
  static py::exception<granuflow::ConfigError> config_error(m, "ConfigError", PyExc_ValueError);
  static py::exception<granuflow::SolverError> solver_error(m, "SolverError", PyExc_RuntimeError);
  static py::exception<granuflow::CalibrationError> calib_error(m, "CalibrationError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const granuflow::SolverError& e) {
      py::object err = py::reinterpret_borrow<py::object>(solver_error.ptr())(e.what());
      err.attr("t") = e.t();
      err.attr("unit") = e.unit();
      err.attr("worst_residual") = e.worst_residual();
      PyErr_SetObject(solver_error.ptr(), err.ptr());
    } catch (const granuflow::ConfigError& e) {
      config_error(e.what());
    } catch (const granuflow::CalibrationError& e) {
      calib_error(e.what());
    } catch (const granuflow::Interrupted& e) {
      // Python's own KeyboardInterrupt, raised by its handler while the run was polling (interrupt_poll.hpp); a run
      // stopped by another thread's interrupt gets one naming where it stopped
      if (!PyErr_Occurred()) PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    }
  });
  // The unit database is read on a thread of its own while the interpreter goes on importing (issue 32: 5 ms of a
  // 0.1 s run); the first scene loaded waits for it if it is not done, and so does a fork() (quantity.cpp: a child
  // would otherwise find its lock held by a thread it does not have). Detached: it ends by itself within
  // milliseconds, and an interpreter that exits sooner ends it.
  std::thread([] {
    try {
      granuflow::load_unit_database();
    } catch (...) {  // the first unit parsed reports a missing database, naming it
    }
  }).detach();
  m.def("allocator_tuned", &granuflow::python::allocator_tuned,
        "Whether importing granuflow set glibc's malloc to keep freed blocks for the next solve (allocator.cpp; "
        "not when the environment configures malloc itself or sets GRANUFLOW_MALLOC_TUNING=0).");
  m.def("interrupt", &granuflow::request_interrupt,
        "Stops the core's runs in progress on every thread, as Ctrl-C does (each ends with KeyboardInterrupt): for "
        "Python code that waits on threads which run them, where Python raised the interrupt itself.");
  granuflow::python::register_flowsheet(m);
  granuflow::python::register_kernels(m);
  granuflow::python::register_reference(m);
  granuflow::python::register_measured_psd(m);
  granuflow::python::register_montecarlo(m);
  granuflow::python::register_plugins(m);
  granuflow::python::register_files(m);
  granuflow::python::register_sweep_batch(m);
  granuflow::python::register_result(m);
}
