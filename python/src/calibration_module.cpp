// granuflow._calibration: the calibration bindings (register_calibration.cpp) in an extension of their own, imported
// on first use, so that a run that never calibrates never loads Ceres, SuiteSparse and BLAS (issue 32: 8 ms of CPU
// at the start of every `granuflow run`). The scene type, the exception types and their translation come from
// granuflow._core, imported first.
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace granuflow::python {
void register_calibration(py::module_& m);
}  // namespace granuflow::python

PYBIND11_MODULE(_calibration, m) {
  m.doc() = "granuflow calibration core (use granuflow.calibration and Flowsheet.calibrate)";
  py::module_::import("granuflow._core");
  granuflow::python::register_calibration(m);
}
