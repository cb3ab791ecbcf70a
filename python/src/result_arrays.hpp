// The arrays of a run handed to Python (register_result.cpp): the solver's vectors, moved, never copied.
#pragma once

#include <pybind11/pybind11.h>

#include <stdexcept>
#include <vector>

namespace granuflow::python {

struct ResultArray {
  std::vector<double> values;
  std::vector<pybind11::ssize_t> shape;
  double* data() {
    static double none = 0.0;  // a buffer of no values still needs an address
    return values.empty() ? &none : values.data();
  }
};

// An empty vector stands for zeros of the shape (a run without sensitivities has none to give).
inline pybind11::object result_array(std::vector<double>&& v, std::vector<pybind11::ssize_t> shape) {
  size_t n = 1;
  for (auto d : shape) n *= static_cast<size_t>(d);
  if (v.empty()) v.assign(n, 0.0);
  if (v.size() != n) throw std::logic_error("result_array: values do not fill the shape");
  return pybind11::cast(ResultArray{std::move(v), std::move(shape)});
}

}  // namespace granuflow::python
