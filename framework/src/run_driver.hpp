// The one segment loop of every dynamic run, over the Stepper interface (stepper.hpp): breakpoints of the inputs and a
// restart at each, output at the requested times (every state, output and sensitivity through the Recorder), the
// solver statistics, and failures as SolverError naming the time, the unit and the worst weighted residual.
#pragma once
#include <chrono>
#include <vector>

#include "granuflow/simulator.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

// Runs `stepper` over [0, opt.t_end] on `sys` (taken from fs for this run) and gives the system back to the
// flowsheet when the run ended normally. `wall0`: when the run started (SimResult::wall_time_s).
SimResult drive(Flowsheet& fs, DaeSystem& sys, const SimOptions& opt, const std::vector<int>& sens_ids,
                Stepper& stepper, std::chrono::steady_clock::time_point wall0);

// The SolverError of a failed step or start: the residual at the integrator's last state, weighted by its error
// weights, names the worst row's unit.
[[noreturn]] void throw_step_failure(const Flowsheet& fs, DaeSystem& sys, const StepFailure& f);

}  // namespace granuflow::detail
