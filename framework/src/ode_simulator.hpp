// Flowsheets that are ODEs y' = f(t, y) (every state differential once explicit units are inlined: population
// balances, tank networks) can run on CVODES (BDF with Newton and the exact Jacobian, or Adams with fixed-point
// iteration) or on ARKODE's explicit Runge-Kutta (Dormand-Prince 5(4)) through the run driver (run_driver.hpp). Every
// unit writes a differential state's residual as y'_k - f_k(y) (unit.hpp), so f(y) = -F(t, y, 0) and df/dy = -dF/dy.
#pragma once
#include <chrono>
#include <stdexcept>
#include <string>

#include "granuflow/simulator.hpp"

namespace granuflow::detail {

// Empty when the flowsheet (explicit units inlined) has only differential states; else names the first algebraic
// state ("unit 'gas', state 'T'").
std::string first_algebraic_state(const Flowsheet& fs);

// The residual turned out not to be of the form y' - f(y) (dF/dy' is not the identity): `auto` falls back to IDAS.
struct NotAnOde : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Runs an ODE flowsheet with `method` (bdf, adams, erk or auto; not ida). With auto, the stiffness at the start
// decides (the spectral radius of df/dy times the run's length against an explicit method's stability limit), and an
// explicit or Adams run that needs far more steps than that predicted (stiffness that developed) continues on BDF
// from where it stopped. SolverStats::method and method_reason say what ran and why.
SimResult simulate_ode(Flowsheet& fs, const SimOptions& opt, Method method,
                       std::chrono::steady_clock::time_point wall0);

}  // namespace granuflow::detail
