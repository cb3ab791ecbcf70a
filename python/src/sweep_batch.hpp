// Batch evaluation of sweep points (contour maps, sweeps): one call solves many parameter points on N threads,
// each thread on its own scene clone, and reduces every run to what a sweep row holds (the final values of the
// wanted outputs, null where the Python Result would report null, and the Result's warnings or failure message),
// so that no point passes through the interpreter. The reductions follow granuflow.result.Result and
// granuflow.outputs exactly (tests/python/test_sweep_batch.py holds them to the per-point path bit for bit).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow::python {

// The solver options a call may override (Flowsheet.simulate's keywords that reach the core).
struct RunOverrides {
  std::optional<double> t_end, rtol, atol;
  std::optional<std::vector<double>> t_out;
  std::optional<int> n_out;
  std::optional<std::string> linear_solver, method;
  std::optional<long> max_steps;
};

// Options checked by the core, the message naming the Python function's keywords instead of the C++ struct's fields
// ("simulate(): t_end = 0 s ..." for "SimOptions.t_end = 0 s ...").
template <class Options>
void validate_as(const Options& o, const std::string& field_prefix, const std::string& call_prefix) {
  try {
    o.validate();
  } catch (const ConfigError& e) {
    std::string m = e.what();
    if (m.rfind(field_prefix, 0) == 0) m = call_prefix + m.substr(field_prefix.size());
    throw ConfigError(m);
  }
}

// The scene's options with `ov` applied (a linear solver or method it does not know: ConfigError naming
// simulate()'s keyword); the caller validates the result with validate_as.
SimOptions run_options(const Scene& s, const RunOverrides& ov);

// A ConfigError found at run time (unit checks, structure), naming the scene file as well.
std::string runtime_config_message(const Scene& s, const std::string& what);

// The constants of granuflow.outputs the reductions use (passed from Python: defined once, there).
struct ResultRules {
  std::vector<std::string> standard_summary_keys;  // STANDARD_SUMMARY_KEYS
  std::vector<std::string> balance_quantities;     // BALANCE_QUANTITIES
  double grid_end_warning = 0.05;                  // GRID_END_WARNING
  double balance_warn_min = 1e-6, balance_warn_factor = 100.0, balance_warn_max = 1e-3, balance_fail = 1e-2;
};

struct BatchRequest {
  std::vector<std::string> params;  // the parameters the points set, in the order they are set
  std::vector<double> base;         // [param]: every point first sets these (SI)
  std::vector<double> values;       // [point][param] (SI), set after the base where `given`
  std::vector<char> given;          // [point][param]
  std::vector<std::string> outputs;
  RunOverrides overrides;
  ResultRules rules;
  size_t n_points() const { return params.empty() ? given.size() : given.size() / params.size(); }
};

struct PointOutcome {
  bool ok = false;
  bool params_set = false;     // every parameter took its value (params holds them)
  std::vector<double> params;  // [param] as read back after setting (SI)
  std::vector<double> values;  // [output]; NaN where undefined (failed point, null summary value)
  std::string message;         // ok: "warning: ..." joined by "; " (may be empty); failed: why
  double solve_time_s = 0.0, wall_time_s = 0.0;
};

// Solves every point of `req`, scenes.size() threads each on its own scene (never shared); `done`, if given, is
// called on the calling thread with the count of finished points about every 0.2 s. SolverError and ConfigError of
// a point make that point failed; any other exception is rethrown once every thread has stopped.
std::vector<PointOutcome> run_batch(const std::vector<Scene*>& scenes, const BatchRequest& req,
                                    const std::function<void(size_t)>& done = {});

}  // namespace granuflow::python
