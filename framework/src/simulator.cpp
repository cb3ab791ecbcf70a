#include "granuflow/simulator.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <utility>

#include "banded_lowrank_solver.hpp"
#include "events.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "granuflow/structure.hpp"
#include "ida_stepper.hpp"
#include "ode_simulator.hpp"
#include "run_common.hpp"
#include "run_driver.hpp"
#include "solver_setup.hpp"

namespace granuflow {

void SimOptions::validate(bool scene_keys) const {
  // Named as the scene file's keys (t_end, output.times[i], solver.rtol ...) or as the fields of SimOptions.
  auto name = [scene_keys](const std::string& field, const std::string& key) {
    return scene_keys ? key : "SimOptions." + field;
  };
  auto fail = [&](const std::string& field, const std::string& key, double v, const std::string& unit,
                  const std::string& rule) { throw ConfigError(violation(name(field, key), v, unit, rule)); };
  if (!(t_end > 0) || !std::isfinite(t_end)) fail("t_end", "t_end", t_end, scene_keys ? "s" : "", "t_end > 0");
  // Below this the integrators' step control breaks down (IDAS takes a stop time of 1e-300 s as behind t = 0).
  if (t_end < kMinEndTime)
    fail("t_end", "t_end", t_end, scene_keys ? "s" : "",
         "t_end >= " + fmt_num(kMinEndTime) + " s (a shorter run is below what the integrators resolve)");
  if (!(rtol > 0 && rtol < 1)) fail("rtol", "solver.rtol", rtol, "", "0 < rtol < 1");
  if (!(atol > 0)) fail("atol", "solver.atol", atol, "", "atol > 0");
  if (max_steps < 1) fail("max_steps", "solver.max_steps", double(max_steps), "", "max_steps >= 1");
  if (!(max_step >= 0)) fail("max_step", "solver.max_step", max_step, scene_keys ? "s" : "", "max_step >= 0");
  if (t_out.empty() && n_out < 2) fail("n_out", "output.n", n_out, "", "n_out >= 2");
  // The results hold every state at every output time: beyond this a request is a typo, not a plan.
  if (t_out.empty() && n_out > kMaxOutputTimes)
    fail("n_out", "output.n", n_out, "", "n_out <= " + std::to_string(kMaxOutputTimes));
  if (t_out.size() > size_t(kMaxOutputTimes))
    fail("t_out", "output.times", double(t_out.size()), "", "at most " + std::to_string(kMaxOutputTimes) + " times");
  for (size_t i = 0; i < t_out.size(); ++i) {
    const std::string field = "t_out[" + std::to_string(i) + "]", key = "output.times[" + std::to_string(i) + "]";
    if (!(t_out[i] >= 0 && t_out[i] <= t_end * (1 + 1e-12)))
      fail(field, key, t_out[i], scene_keys ? "s" : "", "0 <= t_out <= t_end (" + fmt_num(t_end) + " s)");
    if (i > 0 && !(t_out[i] > t_out[i - 1]))
      fail(field, key, t_out[i], scene_keys ? "s" : "", "t_out increasing (previous " + fmt_num(t_out[i - 1]) + " s)");
  }
  for (size_t i = 0; i < checkpoints.size(); ++i) {
    const std::string field = "checkpoints[" + std::to_string(i) + "]";
    if (!(checkpoints[i] > 0 && checkpoints[i] < t_end))
      fail(field, field, checkpoints[i], "s", "0 < checkpoint < t_end (" + fmt_num(t_end) + " s)");
    if (i > 0 && !(checkpoints[i] > checkpoints[i - 1]))
      fail(field, field, checkpoints[i], "s",
           "checkpoints increasing (previous " + fmt_num(checkpoints[i - 1]) + " s)");
  }
}

namespace {

constexpr std::array<std::pair<Method, const char*>, 5> kMethods{{{Method::kAuto, "auto"},
                                                                  {Method::kIda, "ida"},
                                                                  {Method::kBdf, "bdf"},
                                                                  {Method::kAdams, "adams"},
                                                                  {Method::kErk, "erk"}}};
constexpr std::array<std::pair<LinearSolverChoice, const char*>, 6> kLinearSolvers{
    {{LinearSolverChoice::kAuto, "auto"},
     {LinearSolverChoice::kDense, "dense"},
     {LinearSolverChoice::kSparse, "sparse"},
     {LinearSolverChoice::kGmres, "gmres"},
     {LinearSolverChoice::kBanded, "banded"},
     {LinearSolverChoice::kClassLocal, "class_local"}}};

template <class E, size_t N>
E parse_choice(const std::array<std::pair<E, const char*>, N>& table, const std::string& text, const std::string& key) {
  std::string allowed;
  for (const auto& [e, name] : table) {
    if (text == name) return e;
    allowed += (allowed.empty() ? "" : ", ") + std::string(name);
  }
  throw ConfigError(key + " = '" + text + "': not one of " + allowed);
}

template <class E, size_t N>
const char* choice_name(const std::array<std::pair<E, const char*>, N>& table, E e) {
  for (const auto& [v, name] : table)
    if (v == e) return name;
  return "?";
}

}  // namespace

Method parse_method(const std::string& text, const std::string& key) { return parse_choice(kMethods, text, key); }
LinearSolverChoice parse_linear_solver(const std::string& text, const std::string& key) {
  return parse_choice(kLinearSolvers, text, key);
}
const char* to_string(Method m) { return choice_name(kMethods, m); }
const char* to_string(LinearSolverChoice c) { return choice_name(kLinearSolvers, c); }

namespace {

using namespace detail;

// Whether an algebraic unknown belongs to a size class (a class-local Jacobian may lack its couplings).
bool algebraic_classes(const DaeSystem& sys) {
  const std::vector<double> id = sys.differential_id();
  const ClassStructure st = class_structure(sys);
  for (int i = 0; i < sys.size(); ++i)
    if (id[i] == 0.0 && st.cls[i] >= 0) return true;
  return false;
}

SimResult simulate_ida(Flowsheet& fs, const SimOptions& opt, const std::string& reason,
                       std::chrono::steady_clock::time_point wall0) {
  // Explicit units are inlined whenever the system is solved densely.
  const LinearSolverKind kind =
      choose_linear_solver(fs, opt.linear_solver, opt.dense_limit, true, !opt.sensitivities.empty());
  const bool dense = kind != LinearSolverKind::kSparse && kind != LinearSolverKind::kGmres;
  if (kind == LinearSolverKind::kGmres && !opt.sensitivities.empty())
    throw ConfigError("sensitivities need a direct linear solver (solver.linear_solver: dense or sparse), not gmres");
  // The sensitivity equations share the Newton matrix, and their corrector is held to the exact one.
  if (kind == LinearSolverKind::kClassLocal && !opt.sensitivities.empty())
    throw ConfigError(
        "sensitivities need the exact Newton matrix (solver.linear_solver: dense, sparse or banded), "
        "not class_local");
  const std::shared_ptr<DaeSystem> held = fs.take_system(dense);
  DaeSystem& sys = *held;
  const int n = sys.size();
  if (n == 0) throw ConfigError("flowsheet '" + fs.name() + "' has no states to integrate");
  // The inlined system's Jacobian at the initial values serves the structural check and the consistent start.
  std::vector<double> j0;
  if (sys.inlined()) {
    std::vector<double> y_init, yp_init(n, 0.0);
    sys.initial_values(y_init);
    j0.resize(size_t(n) * n);
    // Both read its algebraic block only: with the class-local solver, and no algebraic state per class, the
    // class-local Jacobian has that block exact and costs a third less at 80 classes.
    sys.set_classes_local(kind == LinearSolverKind::kClassLocal && !algebraic_classes(sys));
    sys.jacobian(0.0, y_init.data(), yp_init.data(), 0.0, j0.data(), nullptr);
    sys.set_classes_local(false);
  }
  check_algebraic_structure(sys, j0.empty() ? nullptr : j0.data());  // names an unsolvable algebraic part
  if (interrupt_requested()) throw Interrupted(0.0);                 // the set-up of a large flowsheet can take seconds
  const std::vector<int> sens_ids = sensitivity_ids(fs, opt);
  check_events(fs, opt.events, opt.sensitivities);
  IdaStepper stepper(sys, opt, kind, sens_ids, std::move(j0), reason);
  return drive(fs, sys, opt, sens_ids, stepper, wall0);
}

SimResult simulate_any(Flowsheet& fs, const SimOptions& opt) {
  opt.validate();
  if (!fs.finalized()) fs.finalize();
  fs.check_units();  // every unit at the values of the run, inputs at each of their knots
  const auto wall0 = std::chrono::steady_clock::now();
  if (opt.method == Method::kIda) return simulate_ida(fs, opt, "asked for (solver.method)", wall0);
  // Events, checkpoints and restarts run on IDAS's root finding and restarts (events_and_checkpoints.md).
  const bool ida_only = !opt.events.empty() || !opt.checkpoints.empty() || !opt.restart_file.empty();
  if (ida_only && opt.method != Method::kAuto)
    throw ConfigError(std::string("solver.method = '") + to_string(opt.method) +
                      "': events, checkpoints and restarts need IDAS (solver.method: auto or ida)");
  if (ida_only) return simulate_ida(fs, opt, "events, checkpoints or a restart: IDAS", wall0);
  const std::string algebraic = detail::first_algebraic_state(fs);
  if (!algebraic.empty()) {
    if (opt.method == Method::kAdams || opt.method == Method::kErk)
      throw ConfigError(std::string("solver.method = '") + to_string(opt.method) + "' needs an ODE, but flowsheet '" +
                        fs.name() + "' has algebraic states (" + algebraic + "): use auto, bdf or ida");
    return simulate_ida(fs, opt, "a DAE (algebraic states, e.g. " + algebraic + "): IDAS", wall0);
  }
  try {
    return detail::simulate_ode(fs, opt, opt.method, wall0);
  } catch (const detail::NotAnOde& e) {
    if (opt.method != Method::kAuto && opt.method != Method::kBdf)
      throw ConfigError(std::string("solver.method = '") + to_string(opt.method) + "': flowsheet '" + fs.name() +
                        "' is not an explicit ODE (" + e.what() + "): use auto or ida");
    return simulate_ida(fs, opt, std::string("an ODE, but ") + e.what() + ": IDAS", wall0);
  }
}

}  // namespace

SimResult simulate(Flowsheet& fs, const SimOptions& opt) {
  return interruptible([&] { return simulate_any(fs, opt); });
}

}  // namespace granuflow
