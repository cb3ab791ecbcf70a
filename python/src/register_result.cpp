// A run's arrays as the core hands them to Python, and the reductions Result computes from them
// (result_reductions.hpp). The arrays are plain buffers: NumPy wraps them without a copy when a caller asks for
// res.y, and a plain `granuflow run` reads them here without importing NumPy at all (issue 32: NumPy's import alone
// took longer than the whole run).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include "result_arrays.hpp"
#include "result_reductions.hpp"

namespace py = pybind11;

namespace granuflow::python {
namespace {

BlockView view_of(const py::buffer& b, const char* what) {
  const py::buffer_info info = b.request();
  if (info.format != py::format_descriptor<double>::format() || info.itemsize != sizeof(double) ||
      (info.ndim != 1 && info.ndim != 2))
    throw py::type_error(std::string(what) + ": expected a 1-D or 2-D buffer of float64 (format 'd'), got format '" +
                         info.format + "' with " + std::to_string(info.ndim) + " dimensions");
  BlockView v;
  v.base = static_cast<const char*>(info.ptr);
  v.rows = info.shape[0];
  v.row_stride = info.strides[0];
  v.cols = info.ndim == 2 ? info.shape[1] : 1;
  v.col_stride = info.ndim == 2 ? info.strides[1] : 0;
  return v;
}

// Python's index rules (k < 0 counts from the end), an IndexError naming the call outside them.
std::ptrdiff_t checked(std::ptrdiff_t k, std::ptrdiff_t n, const char* what, const char* kind) {
  if (k < 0) k += n;
  if (k < 0 || k >= n)
    throw py::index_error(std::string(what) + ": " + kind + " " + std::to_string(k) + " outside 0.." +
                          std::to_string(n - 1));
  return k;
}
std::ptrdiff_t column_index(const BlockView& v, std::ptrdiff_t j, const char* what) {
  return checked(j, v.cols, what, "column");
}
std::ptrdiff_t row_index(const BlockView& v, std::ptrdiff_t k, const char* what) {
  return checked(k, v.rows, what, "row");
}

py::list row(const py::buffer& b, std::ptrdiff_t k) {
  const BlockView v = view_of(b, "row");
  k = row_index(v, k, "row");
  py::list out(v.cols);
  for (std::ptrdiff_t j = 0; j < v.cols; ++j) out[j] = v(k, j);
  return out;
}

// Result's timeseries.csv rows: t, t / 60, then per listed column (block, column) its value (x - shift) / scale,
// each as Python's "%.10g" % x (std::to_chars at precision 10; a NaN is "nan" whatever its sign bit).
std::string csv_table(const py::buffer& t, const std::vector<py::buffer>& blocks,
                      const std::vector<std::pair<int, std::ptrdiff_t>>& columns, const std::vector<double>& shift,
                      const std::vector<double>& scale) {
  const BlockView tv = view_of(t, "csv_table: t");
  std::vector<BlockView> bv;
  for (const auto& b : blocks) {
    bv.push_back(view_of(b, "csv_table: block"));
    if (bv.back().rows != tv.rows) throw py::value_error("csv_table: a block's rows differ from the times'");
  }
  if (shift.size() != columns.size() || scale.size() != columns.size())
    throw py::value_error("csv_table: one shift and one scale per column");
  for (const auto& [k, j] : columns)
    if (k < 0 || k >= static_cast<int>(bv.size()) || j < 0 || j >= bv[k].cols)
      throw py::index_error("csv_table: column (" + std::to_string(k) + ", " + std::to_string(j) + ") not in a block");
  std::string out;
  py::gil_scoped_release release;
  out.reserve(static_cast<size_t>(tv.rows) * (columns.size() + 2) * 12);
  char buf[32];
  auto put = [&](double x) {
    if (std::isnan(x)) {
      out += "nan";
    } else {
      const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 10);
      out.append(buf, r.ptr);
    }
  };
  for (std::ptrdiff_t i = 0; i < tv.rows; ++i) {
    const double ti = tv(i, 0);
    put(ti);
    out += ',';
    put(ti / 60.0);
    for (size_t c = 0; c < columns.size(); ++c) {
      out += ',';
      put((bv[columns[c].first](i, columns[c].second) - shift[c]) / scale[c]);
    }
    out += '\n';
  }
  return out;
}

}  // namespace

void register_result(py::module_& m) {
  py::class_<ResultArray>(m, "ResultArray", py::buffer_protocol(),
                          "An array of a run as the core made it (float64, C order): numpy.asarray wraps it without a "
                          "copy; memoryview reads single values.")
      .def_buffer([](ResultArray& a) -> py::buffer_info {
        std::vector<py::ssize_t> strides(a.shape.size(), sizeof(double));
        for (size_t d = a.shape.size(); d-- > 1;) strides[d - 1] = strides[d] * a.shape[d];
        return py::buffer_info(a.data(), sizeof(double), py::format_descriptor<double>::format(),
                               static_cast<py::ssize_t>(a.shape.size()), a.shape, strides);
      })
      .def_property_readonly("shape", [](const ResultArray& a) { return py::tuple(py::cast(a.shape)); })
      .def("__len__", [](const ResultArray& a) { return a.shape.empty() ? 0 : a.shape[0]; });
  m.def("row", &row, py::arg("array"), py::arg("k"), "Row k of a 1-D or 2-D float64 buffer as a list of floats.");
  m.def(
      "column_max",
      [](const py::buffer& b, std::ptrdiff_t j) {
        const BlockView v = view_of(b, "column_max");
        if (v.rows == 0) throw py::value_error("column_max: no rows");
        return column_max(v, column_index(v, j, "column_max"));
      },
      py::arg("array"), py::arg("j"), "The largest value of column j (NaN if the column holds one), as numpy.max.");
  m.def(
      "columns_equal",
      [](const py::buffer& a, std::ptrdiff_t i, const py::buffer& b, std::ptrdiff_t j) {
        const BlockView va = view_of(a, "columns_equal"), vb = view_of(b, "columns_equal");
        return columns_equal(va, column_index(va, i, "columns_equal"), vb, column_index(vb, j, "columns_equal"));
      },
      py::arg("a"), py::arg("i"), py::arg("b"), py::arg("j"),
      "Column i of a equals column j of b at every row, as numpy.array_equal.");
  m.def(
      "end_fractions",
      [](const py::buffer& b, const std::vector<std::ptrdiff_t>& mass_cols, const std::vector<std::ptrdiff_t>& ends) {
        const BlockView v = view_of(b, "end_fractions");
        if (v.rows == 0 || mass_cols.empty()) throw py::value_error("end_fractions: no rows or no class columns");
        for (auto j : mass_cols) column_index(v, j, "end_fractions");
        std::vector<std::ptrdiff_t> e;
        for (auto k : ends) {
          const auto n = static_cast<std::ptrdiff_t>(mass_cols.size());
          if (k < -n || k >= n) throw py::index_error("end_fractions: end " + std::to_string(k) + " not a class");
          e.push_back(k < 0 ? k + n : k);
        }
        return end_fractions(v, mass_cols, e);
      },
      py::arg("array"), py::arg("mass_cols"), py::arg("ends"),
      "(first, last, max over rows) of the mass fraction of each end (position in mass_cols) among mass_cols.");
  m.def("csv_table", &csv_table, py::arg("t"), py::arg("blocks"), py::arg("columns"), py::arg("shift"),
        py::arg("scale"), "timeseries.csv's rows: t, t/60 and (block[:, j] - shift) / scale per (block, j).");
}

}  // namespace granuflow::python
