// granuflow._core.sweep_batch: the points of a sweep solved on N threads without the interpreter (sweep_batch.hpp).
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "interrupt_poll.hpp"
#include "sweep_batch.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

template <class T>
std::optional<T> opt(const py::dict& d, const char* key) {
  if (!d.contains(key) || d[key].is_none()) return std::nullopt;
  return d[key].cast<T>();
}

RunOverrides overrides_of(const py::dict& d) {
  RunOverrides ov;
  ov.t_end = opt<double>(d, "t_end"), ov.rtol = opt<double>(d, "rtol"), ov.atol = opt<double>(d, "atol");
  ov.t_out = opt<std::vector<double>>(d, "t_out"), ov.n_out = opt<int>(d, "n_out");
  ov.linear_solver = opt<std::string>(d, "linear_solver"), ov.method = opt<std::string>(d, "method");
  ov.max_steps = opt<long>(d, "max_steps");
  return ov;
}

ResultRules rules_of(const py::dict& d) {
  ResultRules r;
  r.standard_summary_keys = d["STANDARD_SUMMARY_KEYS"].cast<std::vector<std::string>>();
  r.balance_quantities = d["BALANCE_QUANTITIES"].cast<std::vector<std::string>>();
  r.grid_end_warning = d["GRID_END_WARNING"].cast<double>();
  r.balance_warn_min = d["BALANCE_WARN_MIN"].cast<double>();
  r.balance_warn_factor = d["BALANCE_WARN_FACTOR"].cast<double>();
  r.balance_warn_max = d["BALANCE_WARN_MAX"].cast<double>();
  r.balance_fail = d["BALANCE_FAIL"].cast<double>();
  return r;
}

py::dict sweep_batch(const std::vector<Scene*>& scenes, std::vector<std::string> params, std::vector<double> base,
                     const py::array_t<double, py::array::c_style | py::array::forcecast>& values,
                     const py::array_t<bool, py::array::c_style | py::array::forcecast>& given,
                     std::vector<std::string> outputs, const py::dict& simulate, const py::dict& rules,
                     const std::optional<py::function>& progress) {
  BatchRequest req;
  const size_t np = params.size();
  if (scenes.empty()) throw ConfigError("sweep_batch: no scene to solve on");
  for (size_t a = 0; a < scenes.size(); ++a)  // a thread sets the parameters of its scene: never two on one
    for (size_t b = a + 1; b < scenes.size(); ++b)
      if (scenes[a] == scenes[b])
        throw ConfigError("sweep_batch: scenes[" + std::to_string(a) + "] and scenes[" + std::to_string(b) +
                          "] are the same scene: give each thread its own clone");
  if (base.size() != np || values.ndim() != 2 || given.ndim() != 2 || size_t(values.shape(1)) != np ||
      values.shape(0) != given.shape(0) || given.shape(1) != values.shape(1))
    throw ConfigError("sweep_batch: base [param], values and given [point, param] do not fit the parameters");
  req.params = std::move(params), req.base = std::move(base), req.outputs = std::move(outputs);
  req.values.assign(values.data(), values.data() + values.size());
  req.given.assign(given.data(), given.data() + given.size());
  if (np == 0) req.given.resize(values.shape(0));  // n_points() counts the rows
  req.overrides = overrides_of(simulate);
  req.rules = rules_of(rules);
  std::vector<PointOutcome> out;
  {
    const CoreCall call;
    std::function<void(size_t)> done;
    if (progress)
      done = [&progress](size_t k) {
        py::gil_scoped_acquire acquire;
        (*progress)(k);
      };
    out = run_batch(scenes, req, done);
  }
  const auto n = static_cast<py::ssize_t>(out.size());
  const auto no = static_cast<py::ssize_t>(req.outputs.size());
  py::array_t<double> vals({n, no}), prm({n, static_cast<py::ssize_t>(np)}), solve(n), wall(n);
  py::array_t<bool> ok(n), set(n);
  py::list messages;
  for (py::ssize_t i = 0; i < n; ++i) {
    const PointOutcome& p = out[i];
    for (py::ssize_t k = 0; k < no; ++k) vals.mutable_at(i, k) = p.ok ? p.values[k] : std::nan("");
    for (size_t k = 0; k < np; ++k) prm.mutable_at(i, k) = p.params_set ? p.params[k] : std::nan("");
    solve.mutable_at(i) = p.ok ? p.solve_time_s : std::nan("");
    wall.mutable_at(i) = p.wall_time_s;
    ok.mutable_at(i) = p.ok, set.mutable_at(i) = p.params_set;
    messages.append(p.message);
  }
  return py::dict("values"_a = vals, "params"_a = prm, "ok"_a = ok, "params_set"_a = set, "message"_a = messages,
                  "solve_time_s"_a = solve, "wall_time_s"_a = wall);
}

}  // namespace

void register_sweep_batch(py::module_& m) {
  m.def("sweep_batch", &sweep_batch, "scenes"_a, "params"_a, "base"_a, "values"_a, "given"_a, "outputs"_a, "simulate"_a,
        "rules"_a, "progress"_a = py::none(),
        "Solves the points [point, param] (each sets `base`, then its `given` values) on len(scenes) threads, one "
        "scene each (never shared), with the GIL released; returns the final values of `outputs` per point (NaN "
        "where null), the parameter values read back, ok, message (warnings or why it failed) and times. "
        "`progress(done)` is called about every 0.2 s.");
}

}  // namespace granuflow::python
