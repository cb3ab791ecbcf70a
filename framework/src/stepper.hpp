// One integrator behind the run driver (run_driver.hpp): IDAS for any DAE (ida_stepper.hpp), CVODES and ARKODE for
// flowsheets that are ODEs (ode_steppers.hpp). The driver owns what every run shares: the segments between input
// breakpoints, the output times, the recording, the statistics common to all and the SolverError of a failure. A
// stepper owns its SUNDIALS memory and vectors and what differs between integrators: how a segment starts (IDAS: a
// consistent start; the others: a restart from where the last segment ended), how the state, derivatives,
// quadratures and sensitivities are read at an output time, and its own counts.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "granuflow/simulator.hpp"

namespace granuflow::detail {

// The integrator's values at an output time, as the Recorder reads them; null where there are none.
struct Sample {
  const double* y = nullptr;
  const double* yp = nullptr;
  const double* q = nullptr;
  const double* const* yS = nullptr;
  const double* const* qS = nullptr;
};

// The integrator's last state when a step or a start failed: the driver evaluates the residual there to name the
// unit and the worst weighted residual.
struct StepFailure {
  std::string what;       // the call that failed, e.g. "IDASolve", "integration (erk)"
  std::string flag_text;  // SUNDIALS' name of the flag, and the last error a callback or the integrator reported
  double t = 0.0;
  const double* y = nullptr;    // the unknowns at t
  const double* yp = nullptr;   // their derivatives at t (an ODE integrator's interpolated y')
  std::vector<double> weights;  // the integrator's error weights, 1 / (rtol |y_i| + atol_i)
};

// Adds an integrator's counts (steps, setups, iterations, failures) to `to`.
inline void add_counts(SolverStats& to, const SolverStats& from) {
  to.steps += from.steps, to.linear_setups += from.linear_setups, to.nonlinear_iterations += from.nonlinear_iterations;
  to.error_test_failures += from.error_test_failures, to.nonlinear_failures += from.nonlinear_failures;
  to.linear_iterations += from.linear_iterations, to.preconditioner_setups += from.preconditioner_setups;
  to.linear_failures += from.linear_failures;
}

// Everything an integrator restarts from at the start of a segment (a checkpoint, checkpoint.hpp): the unknowns, their
// derivatives, the quadratures and the sensitivities of each, at time t.
struct StepperState {
  double t = 0.0;
  std::vector<double> y, yp, q;
  std::vector<std::vector<double>> yS, ypS, qS;
};

// What changes the sensitivities at a state event (events_run.hpp): for a root at t* of g(t, y, p), the event time
// moves with p by tau_k = dt*/dp_k = -(dg/dp_k) / (dg/dt), and a state that stays continuous across the event while
// its rate jumps from y'- to y'+ has s+ = s- + (y'- - y'+) tau_k (the same for the quadratures).
struct SensitivityJump {
  std::vector<double> tau;                     // per sensitivity parameter
  std::vector<double> yp_before, qdot_before;  // the integrator's y' and the quadrature rates just before the event
};

// Root functions of the state events: g_i(t, y, y') for each event; 0 on success.
using RootFunction = std::function<int(double, const double*, const double*, double*)>;

class Stepper {
 public:
  virtual ~Stepper() = default;
  // Starts segment `seg` over [t0, t1] (seg > 0: after a breakpoint, from where the last segment ended) and sets the
  // stop time t1. Returns a SUNDIALS flag, < 0 on failure (failure() then tells where).
  virtual int begin_segment(size_t seg, double t0, double t1, SolverStats& stats) = 0;
  // Advances towards tout, never past the segment's end; t: where it stopped. Returns the flag, < 0 on failure.
  virtual int advance(double tout, double& t) = 0;
  // After advance returned `flag` at t: whether the segment [.., t1] is done.
  virtual bool segment_done(int flag, double t, double t1) const = 0;
  // The values at output time t, just reached (or the segment's start).
  virtual Sample sample(double t) = 0;
  // Reads what the next segment restarts from (quadratures, sensitivities) at the end t1 of a segment from t0.
  virtual void end_segment(double t0, double t1) = 0;
  virtual StepFailure failure(int flag) = 0;
  // The stepper's counts, which integrator ran and why, the linear solver it used.
  virtual void finish(SolverStats& stats) = 0;

  // State events (IDAS; the driver refuses them before another stepper is made): `n` root functions and their
  // directions (+1 rising, -1 falling, 0 both).
  virtual void set_roots(int, RootFunction, const std::vector<int>&) {}
  virtual bool root_found(int) const { return false; }
  // After root_found: which root functions crossed (non-zero entries).
  virtual std::vector<int> roots() { return {}; }
  // Applied when the next segment starts, once its consistent values are known.
  virtual void jump_sensitivities(SensitivityJump) {}
  // Checkpoints: the values at the end of a segment, just read by end_segment(); and a start from such values, the
  // next begin_segment() then restarting from them as from the end of a segment of this run.
  virtual bool save(StepperState&) { return false; }
  virtual void restore(const StepperState&) {}
};

}  // namespace granuflow::detail
