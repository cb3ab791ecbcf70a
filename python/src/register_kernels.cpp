// Aggregation kernels written in Python, for prototyping (kernels/aggregation/callback.hpp). A callable
// fn(diameters_m, volumes_m3) -> (n, n) array of beta (1/s per pair) is added to the process-wide kernel registry
// under its name, so a pbm_batch unit selects it like a compiled kernel (settings: {aggregation: NAME}).
//
// Cost: the GIL is taken for every evaluation. The kernel reads only the pivot sizes (state-independent), so
// pbm_batch evaluates it once per run (Unit::configure), never per residual. Every returned matrix is checked
// (shape, finite, >= 0, symmetric to 1e-10 relative) and a failure is a ConfigError (Python ValueError) naming
// the kernel, the entry and the rule; an exception raised by the callable becomes one too, with its type and text.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include "granuflow/errors.hpp"
#include "kernels/aggregation/callback.hpp"
#include "kernels/registry.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

using kernels::ClassState;

// A strong reference to a Python callable that may outlive the interpreter (the registry is a C++ static,
// destroyed after Python has finalized): released under the GIL while Python runs, leaked after.
struct PyCallable {
  PyObject* fn;
  explicit PyCallable(const py::function& f) : fn(f.inc_ref().ptr()) {}
  PyCallable(const PyCallable&) = delete;
  PyCallable& operator=(const PyCallable&) = delete;
  ~PyCallable() {
    if (Py_IsInitialized()) {
      py::gil_scoped_acquire gil;
      Py_XDECREF(fn);
    }
  }
};

// The current callable of a kernel registered from Python; register_kernel(..., replace=True) swaps it. A
// flowsheet keeps the callable it was built with.
struct Slot {
  std::mutex mutex;
  std::shared_ptr<PyCallable> fn;
  std::shared_ptr<PyCallable> get() {
    std::lock_guard<std::mutex> lock(mutex);
    return fn;
  }
  void set(std::shared_ptr<PyCallable> f) {
    std::lock_guard<std::mutex> lock(mutex);
    fn = std::move(f);
  }
};

std::map<std::string, std::shared_ptr<Slot>>& python_kernels() {
  static std::map<std::string, std::shared_ptr<Slot>> m;  // accessed with the GIL held
  return m;
}

std::string where_of(const std::string& name) { return "aggregation kernel '" + name + "' (Python)"; }

std::string format_entry(int i, int j) { return "beta[" + std::to_string(i) + ", " + std::to_string(j) + "]"; }

// Checks the matrix returned by the callable and copies it into beta (symmetrized: (b + b^T) / 2).
void check_and_copy(const std::string& where, const py::handle& out, int n, double* beta) {
  if (out.is_none())
    throw ConfigError(where + ": returned None, expected a real (" + std::to_string(n) + ", " + std::to_string(n) +
                      ") array (one row and one column per size class)");
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(out);
  if (!a) {
    PyErr_Clear();
    throw ConfigError(where + ": returned " + std::string(py::str(py::type::handle_of(out).attr("__name__"))) +
                      ", expected a real (" + std::to_string(n) + ", " + std::to_string(n) +
                      ") array (one row and one column per size class)");
  }
  if (a.ndim() != 2 || a.shape(0) != n || a.shape(1) != n) {
    std::ostringstream os;
    os << where << ": returned an array of shape (";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) os << (k ? ", " : "") << a.shape(k);
    os << (a.ndim() == 1 ? ",)" : ")") << ", expected (" << n << ", " << n
       << ") (one row and one column per size class)";
    throw ConfigError(os.str());
  }
  const double* b = a.data();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = b[size_t(i) * n + j];
      if (!std::isfinite(x)) throw ConfigError(violation(where + ": " + format_entry(i, j), x, "1/s", "beta finite"));
      if (x < 0) throw ConfigError(violation(where + ": " + format_entry(i, j), x, "1/s", "beta >= 0"));
    }
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const double x = b[size_t(i) * n + j], y = b[size_t(j) * n + i];
      if (std::abs(x - y) > 1e-10 * (x + y)) {
        std::ostringstream os;
        os.precision(12);
        os << where << ": " << format_entry(i, j) << " = " << x << " 1/s but " << format_entry(j, i) << " = " << y
           << " 1/s: violates symmetry beta[i, j] = beta[j, i] (relative 1e-10)";
        throw ConfigError(os.str());
      }
      beta[size_t(i) * n + j] = beta[size_t(j) * n + i] = 0.5 * (x + y);
    }
  for (int i = 0; i < n; ++i) beta[size_t(i) * n + i] = b[size_t(i) * n + i];
}

kernels::BetaCallback make_callback(const std::string& name, std::shared_ptr<PyCallable> f,
                                    std::vector<std::string> params) {
  return [where = where_of(name), f, params](const ClassState<double>& s, const double* p, double* beta) {
    py::gil_scoped_acquire gil;
    const int n = s.n;
    py::array_t<double> d(n, s.diameter), v(n, s.volume);  // copies: the grid stays untouched
    d.attr("setflags")("write"_a = false);
    v.attr("setflags")("write"_a = false);
    py::dict kw;  // the kernel's parameters by name, in SI
    for (size_t k = 0; k < params.size(); ++k) kw[py::str(params[k])] = p[k];
    py::object out;
    try {
      out = py::reinterpret_borrow<py::object>(f->fn)(d, v, **kw);
    } catch (py::error_already_set& e) {
      const std::string type = py::str(e.type().attr("__name__"));
      const std::string text = py::str(e.value());
      throw ConfigError(where + ": fn(diameters_m, volumes_m3) raised " + type + (text.empty() ? "" : ": " + text));
    }
    check_and_copy(where, out, n, beta);
  };
}

void register_kernel(const std::string& name, const py::function& fn, const std::vector<ParamSpec>& params,
                     const std::string& description, bool replace) {
  auto& reg = kernels::registries().aggregation;
  auto& mine = python_kernels();
  auto f = std::make_shared<PyCallable>(fn);
  if (reg.contains(name)) {
    auto it = mine.find(name);
    if (it == mine.end())
      throw ConfigError("aggregation kernel '" + name + "' is built in and cannot be replaced; choose another name");
    if (!replace)
      throw ConfigError("aggregation kernel '" + name +
                        "' is already registered (from Python); pass replace=True to swap its function");
    it->second->set(std::move(f));
    return;
  }
  if (name.empty() || name == "none" || name.find_first_of(" \t\n:,{}[]#") != std::string::npos)
    throw ConfigError("aggregation kernel name '" + name +
                      "': violates a non-empty name other than 'none' without spaces or any of :,{}[]#");
  auto slot = std::make_shared<Slot>();
  slot->set(std::move(f));
  std::vector<std::string> names;
  for (const auto& p : params) names.push_back(p.name);
  // The factory takes the callable current at flowsheet build time (register_callback_kernel would fix it now).
  reg.add(name, (description.empty() ? "Python kernel" : description) + " (callable, prototyping)",
          [name, slot, params, names] {
            return std::make_unique<kernels::CallbackKernel>(params, kernels::ClassNeeds{},
                                                             make_callback(name, slot->get(), names));
          });
  mine.emplace(name, std::move(slot));
}

}  // namespace

void register_kernels(py::module_& m) {
  m.def(
      "register_aggregation_kernel",
      [](const std::string& name, const py::function& fn, const std::vector<py::dict>& params,
         const std::string& description, bool replace) {
        std::vector<ParamSpec> specs;
        for (const auto& d : params)  // checked in granuflow.kernels; here only converted
          specs.push_back({d["name"].cast<std::string>(), d["unit"].cast<std::string>(), d["default"].cast<double>(),
                           d["lower"].cast<double>(), d["upper"].cast<double>(), d["description"].cast<std::string>(),
                           d["source"].cast<std::string>()});
        register_kernel(name, fn, specs, description, replace);
      },
      "name"_a, "fn"_a, py::kw_only(), "params"_a = std::vector<py::dict>{}, "description"_a = "", "replace"_a = false,
      "Add a Python aggregation kernel fn(diameters_m, volumes_m3, **params) -> (n, n) beta in 1/s to the kernel "
      "registry; params: dicts with name, unit (SI), default, lower, upper, description, source.");
  m.def(
      "aggregation_kernels",
      [] {
        const auto& reg = kernels::registries().aggregation;
        py::dict d;
        for (const auto& n : reg.names()) d[py::str(n)] = reg.description(n);
        return d;
      },
      "Registered aggregation kernels (built in and from Python) and their descriptions.");
  m.def(
      "python_kernels",
      [] {
        py::list l;
        for (const auto& [k, s] : python_kernels()) l.append(k);
        return l;
      },
      "Names of the aggregation kernels registered from Python.");
}

}  // namespace granuflow::python
