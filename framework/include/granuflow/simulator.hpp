// Dynamic runs and steady states: one run driver (run_driver.hpp) over the integrators (IDAS, CVODES, ARKODE) with
// consistent starts, exact Jacobians, stops and re-initialization at input breakpoints, output at requested times and
// forward sensitivities w.r.t. named parameters; and a KINSOL steady-state solve. Failures throw SolverError naming
// the time, the unit and the worst residual.
#pragma once
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "granuflow/dae_system.hpp"
#include "granuflow/events.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow {

// Output times per run (output.n, the length of output.times): validate() refuses more.
inline constexpr int kMaxOutputTimes = 100000;
// The shortest run: a nanosecond, far below any time scale of these processes.
inline constexpr double kMinEndTime = 1e-9;  // s

// The integrator (solver.method): ida (IDAS, BDF: any flowsheet); bdf or adams (CVODES) and erk (ARKODE,
// Dormand-Prince 5(4)) for flowsheets that are ODEs (every state differential once explicit units are inlined); auto:
// IDAS for a DAE, for an ODE by its stiffness (ode_simulator.hpp). SolverStats::method says what ran.
enum class Method { kAuto, kIda, kBdf, kAdams, kErk };
// The Newton systems' linear solver (solver.linear_solver). auto: dense up to dense_limit states; beyond, gmres when a
// unit preconditions itself, else dense or sparse by the Jacobian's fill.
enum class LinearSolverChoice { kAuto, kDense, kSparse, kGmres, kBanded, kClassLocal };
// Options are text only at the edges (scene files, Python, the command line): parsed once here, with a ConfigError
// naming `key`, the text and the names allowed.
Method parse_method(const std::string& text, const std::string& key = "solver.method");
LinearSolverChoice parse_linear_solver(const std::string& text, const std::string& key = "solver.linear_solver");
const char* to_string(Method m);
const char* to_string(LinearSolverChoice c);

struct SimOptions {
  double t_end = 0.0;                      // s, > 0
  std::vector<double> t_out;               // output times in [0, t_end], increasing; empty: n_out equispaced
  int n_out = 101;                         // used when t_out is empty
  double rtol = 1e-6;                      // relative tolerance
  double atol = 1e-8;                      // absolute tolerance, multiplied by each state's declared scale
  long max_steps = 200000;                 // per segment between breakpoints
  double max_step = 0.0;                   // s; 0 = no limit
  std::vector<std::string> sensitivities;  // "unit.param" names for forward sensitivities
  // Include the sensitivities in the local error test (IDASetSensErrCon). Off, they are still computed by
  // the staggered corrector at every step of the state, only without their own step-size control: about
  // half the steps, and accurate to roughly the states' tolerance on smooth problems (calibration Jacobians).
  bool sens_error_control = true;
  LinearSolverChoice linear_solver = LinearSolverChoice::kAuto;
  Method method = Method::kAuto;
  int dense_limit = 400;
  std::vector<EventSpec> events;  // state events (events.hpp); a run with events integrates with IDAS
  // Checkpoints: times in (0, t_end) at which the run stops and restarts its integrator (in every run that names
  // them, so that a restart from the file written there is bit-identical); with checkpoint_dir, the state is written
  // there as checkpoint_<t>s.gfckpt. restart_file: resume from such a file instead of starting at t = 0.
  std::vector<double> checkpoints;
  std::string checkpoint_dir;
  std::string restart_file;
  // Throws ConfigError naming the value and the rule, and the field as SimOptions.<field> or, with scene_keys, as the
  // scene file's key.
  void validate(bool scene_keys = false) const;
};

struct SolverStats {
  long steps = 0;
  long residuals = 0;  // residual evaluations (including those inside consistent initialization)
  long jacobians = 0;
  long linear_setups = 0;
  long nonlinear_iterations = 0;
  long error_test_failures = 0;
  long nonlinear_failures = 0;
  long reinits = 0;  // restarts at input breakpoints
  // How IDAS segments (the first and one per breakpoint) found consistent y and y': by the exact Newton on the
  // algebraic states (dense runs whose units keep the residual contract) or by IDACalcIC (the rest, and where that
  // Newton gave up).
  long newton_starts = 0;
  long calcic_starts = 0;
  long states = 0;                 // unknowns of the integrator
  long explicit_states = 0;        // states of explicit units, evaluated inline
  long quadratures = 0;            // integrals of flows, outside the Newton system
  long linear_iterations = 0;      // Krylov iterations (gmres only)
  long preconditioner_setups = 0;  // (gmres only)
  long linear_failures = 0;        // Krylov iterations that did not converge (gmres only)
  std::string linear_solver;
  std::string method;         // the integrator that ran (and, if auto switched mid-run, both)
  std::string method_reason;  // why: asked for, or what auto saw
};

struct SimResult {
  std::vector<double> t;
  std::vector<std::string> state_names;
  std::vector<double> y;   // row-major [time][state]
  std::vector<double> yp;  // row-major [time][state]
  std::vector<std::string> output_names;
  std::vector<double> outputs;  // row-major [time][output]
  std::vector<std::string> sens_params;
  std::vector<double> sens;         // row-major [time][param][state]
  std::vector<double> output_sens;  // row-major [time][param][output], exact (outputs differentiated with Jets)
  SolverStats stats;
  std::vector<EventRecord> events;            // the events that fired, in time order
  std::vector<std::string> checkpoint_files;  // written by this run
  double wall_time_s = 0.0;
  int n_states() const { return static_cast<int>(state_names.size()); }
  double state(size_t time_index, int state) const { return y[time_index * state_names.size() + state]; }
};

SimResult simulate(Flowsheet& fs, const SimOptions& options);

struct SteadyOptions {
  double t = 0.0;                // time at which inputs are evaluated
  double ftol = 1e-10;           // scaled residual tolerance
  long max_iterations = 200;     // Newton iterations per attempt
  long max_pseudo_steps = 2000;  // pseudo-transient steps when Newton from the start fails (0: none)
  bool stability = false;        // eigenvalues of the linearization at the steady state (dense systems)
  void validate() const;
};

struct SteadyResult {
  std::vector<double> y;  // every state (explicit units' evaluated)
  long iterations = 0;    // Newton iterations
  double residual_norm = 0.0;
  std::string method;  // "newton" or "pseudo-transient continuation, then newton"
  long pseudo_steps = 0;
  std::vector<std::string> conserved;  // combinations the start fixes (a batch hold-up ...)
  std::vector<std::string> warnings;   // e.g. the trivial root
  double wall_time_s = 0.0;
  // Reported outputs at the steady state (fs.output_names() order); outputs that integrate a flow over time
  // (quadratures: amounts fed or collected) have no steady value and are NaN.
  std::vector<double> outputs;
  // Per balance quantity (solids, water, energy): the flows across the flowsheet's boundary at the steady state,
  // summed over the quadratures declared as balance in / out (per second: kg/s, J/s).
  std::map<std::string, std::pair<double, double>> boundary_flows;
  // With SteadyOptions::stability: the eigenvalue of the linearized dynamics (algebraic states eliminated) with the
  // largest real part; a positive real part with an imaginary part means the steady state is unstable and the
  // dynamics leave it in growing oscillations of period 2 pi / |imag| (a limit cycle, not a numerical artefact).
  bool stability_known = false;
  double max_real_eigenvalue = 0.0, imag_of_max = 0.0;  // 1/s
  double stability_time_s = 0.0;
};

// Solves F(y, y' = 0) = 0 from the initial values (or from `guess` when given): conserved combinations kept at their
// initial values, Newton (KINSOL, line search), pseudo-transient continuation if Newton fails (steady_state.cpp).
// Throws SolverError when the flowsheet has no steady state (a combination that drifts at a constant rate) or none
// is found. SteadyResult::y is the full state vector; a guess may be full or cover the integrated states only.
SteadyResult solve_steady_state(Flowsheet& fs, const SteadyOptions& options,
                                const std::vector<double>* guess = nullptr);

}  // namespace granuflow
