// Result files from Python: the rows of timeseries.csv formatted here, not value by value in Python (issue 32: the
// 2-D scene's file at 80x80, 139 000 values, took 36 ms of CPU to format in Python, 12 ms here). Python opens and
// names the file, so a folder that cannot be written fails as every other file does.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <charconv>
#include <cmath>
#include <string>

namespace py = pybind11;

namespace granuflow::python {
namespace {

// Each value as Python's "%.10g" % x: std::to_chars at precision 10, which is C's %.10g (both correctly rounded to 10
// digits, the same exponent form) at a fraction of snprintf's cost, but a NaN is "nan" whatever its sign bit (C would
// write "-nan").
std::string csv_rows(const py::array_t<double, py::array::c_style | py::array::forcecast>& data) {
  if (data.ndim() != 2) throw py::value_error("csv_rows: expected a 2-D array of values");
  const auto rows = data.shape(0), cols = data.shape(1);
  const double* v = data.data();
  std::string out;
  out.reserve(static_cast<size_t>(rows * cols) * 12 + static_cast<size_t>(rows));
  py::gil_scoped_release release;
  char buf[32];
  for (py::ssize_t i = 0; i < rows; ++i) {
    for (py::ssize_t j = 0; j < cols; ++j) {
      const double x = v[i * cols + j];
      if (j) out += ',';
      if (std::isnan(x)) {
        out += "nan";
      } else {
        const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 10);
        out.append(buf, r.ptr);
      }
    }
    out += '\n';
  }
  return out;
}

}  // namespace

void register_files(py::module_& m) {
  m.def("csv_rows", &csv_rows, py::arg("data"),
        "The rows of a 2-D array as CSV text, each value as Python's '%.10g' % x, one line per row.");
}

}  // namespace granuflow::python
