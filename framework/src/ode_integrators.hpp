// The ODE integrators behind the run driver's OdeStepper (ode_simulator.cpp): CVODES (BDF with Newton and the exact
// Jacobian or GMRES, or Adams with fixed-point iteration) and ARKODE's explicit Dormand-Prince 5(4). Every unit writes
// a differential state's residual as y'_k - f_k(y) (unit.hpp), so f(y) = -F(t, y, 0) and df/dy = -dF/dy.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/simulator.hpp"
#include "solver_setup.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

// f(t, y) = -F(t, y, 0) and what the SUNDIALS callbacks need around it.
struct OdeUser {
  DaeSystem* sys = nullptr;
  bool dense = true;
  bool gmres = false;  // BDF's Newton systems by GMRES with the units' preconditioners (solver_setup.hpp)
  int n = 0, nq = 0;
  std::vector<int> params;
  std::vector<double> zeros, f, r;
  std::vector<const double*> yS, ypS;
  std::vector<double*> rS, qS;
  std::string last_error;
  unsigned interrupt_calls = 0;  // interrupt_requested(calls)

  Status rhs(double t, const double* y, double* ydot) {
    const Status s = sys->residual(t, y, zeros.data(), ydot);
    for (int i = 0; i < n; ++i) ydot[i] = -ydot[i];
    return s;
  }
};

// One integrator of an ODE run: the OdeStepper hands a run from a non-stiff one to BDF mid-way through these.
class OdeIntegrator {
 public:
  virtual ~OdeIntegrator() = default;
  // Restart at t from y (and q, sensitivities): a segment start, or the state handed over by another stepper.
  virtual void restart(double t, const double* y, const double* q, const std::vector<std::vector<double>>& yS,
                       const std::vector<std::vector<double>>& qS) = 0;
  virtual void set_stop(double t) = 0;
  // Advances towards tout; returns the flag (< 0 failure) with y and t where it stopped.
  virtual int advance(double tout, double* y, double* t) = 0;
  virtual void quadratures(double t, double* q) = 0;
  virtual void sensitivities(double t, std::vector<std::vector<double>>& yS, std::vector<std::vector<double>>& qS) = 0;
  // Adds the counts of every stretch between restarts (a restart zeroes the integrator's own) to s.
  void add_stats(SolverStats& s) const {
    SolverStats c = done_;
    add_current(c);
    add_counts(s, c);
  }
  virtual std::string flag_text(int flag) const = 0;
  virtual bool too_much_work(int flag) const = 0;
  // After a failure: the current time, y' there (interpolated) and the error weights, each of the n unknowns.
  virtual double failed_state(double* yp, double* weights) const = 0;

 protected:
  virtual void add_current(SolverStats& s) const = 0;  // the counts since the last restart
  void bank_counts() { add_current(done_); }           // before a restart
  SolverStats done_;
};

// CVODES: BDF (Newton: dense, sparse or GMRES as the OdeUser says) or Adams (fixed-point iteration); ARKODE's
// Dormand-Prince 5(4). `max_steps`: per output interval.
std::unique_ptr<OdeIntegrator> make_cvode(SUNContext ctx, OdeUser& u, bool bdf, const SimOptions& opt, double t0,
                                          const double* y0, const std::vector<double>& atol,
                                          const std::vector<double>& qatol, long max_steps);
std::unique_ptr<OdeIntegrator> make_erk(SUNContext ctx, OdeUser& u, const SimOptions& opt, double t0, const double* y0,
                                        const std::vector<double>& atol, const std::vector<double>& qatol,
                                        long max_steps);

}  // namespace granuflow::detail
