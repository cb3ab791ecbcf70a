// What every integrator's run shares (simulator.cpp for IDAS, ode_simulator.cpp for CVODES and ARKODE): the
// sensitivity parameters and output times of the options, and the recording of a SimResult at an output time.
#pragma once
#include <string>
#include <vector>

#include "granuflow/dae_system.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow::detail {

// Global ids of SimOptions::sensitivities (constants only: an input-driven parameter has no single value).
std::vector<int> sensitivity_ids(const Flowsheet& fs, const SimOptions& opt);
// SimOptions::t_out, or n_out equispaced times over [0, t_end].
std::vector<double> output_times(const SimOptions& opt);

// Fills a SimResult at output times the same way whatever the integrator: the full state vector (explicit units
// evaluated), the inventory check, reported outputs, and the sensitivities of states and outputs.
class Recorder {
 public:
  Recorder(Flowsheet& fs, DaeSystem& sys, const SimOptions& opt, std::vector<int> sens_ids, SimResult& res);
  // y, yp: the integrator's unknowns and their derivatives at t; q: the quadratures (null when there are none);
  // yS, qS: the sensitivities of y and q to each parameter (null when none were asked for).
  void record(double t, const double* y, const double* yp, const double* q, const double* const* yS,
              const double* const* qS);

 private:
  Flowsheet& fs_;
  DaeSystem& sys_;
  const SimOptions& opt_;
  std::vector<int> sens_ids_;
  SimResult& res_;
  std::vector<double> y_full_, yp_full_, out_, q_zero_;
  std::vector<std::vector<double>> s_full_, dout_, qs_zero_;
  std::vector<std::pair<int, double>> floors_;  // nonnegative inventories: index, lowest value the solver may leave
};

// An inventory below zero by more than the solver can be blamed for means a rate that is not positivity-preserving
// at that state: a SolverError naming the unit, the state and the time.
void check_nonnegative(const Flowsheet& fs, const SimOptions& opt, double t, const std::vector<double>& y_full);

}  // namespace granuflow::detail
