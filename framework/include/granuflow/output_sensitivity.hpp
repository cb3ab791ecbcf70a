// Sensitivities of reported outputs (Unit::report, e.g. bed.d50) with respect to parameters, from the state
// sensitivities of a simulation:
//
//   dz_j/dp_k (t) = (d report_j / d y)(y(t), p) s_k(t) + (d report_j / d p_k)(y(t), p),
//
// where s_k = dy/dp_k are IDAS forward sensitivities of all states (SimResult::sens). report() is an algebraic
// function of the state, not a simulation, so both terms are taken by central differences of
// DaeSystem::report(): the first along the direction s_k (two report() calls per time and parameter, whatever
// the number of states), the second by stepping p_k itself. The step is `rel_step` relative to the states'
// magnitudes (|y_i| + declared scale) and to |p_k|. Characteristic diameters (d10 ... d95) are piecewise
// smooth in the class masses (the cumulative distribution is interpolated between class edges): across a kink
// the central difference returns the mean of the one-sided slopes.
// Contract: report() must not read state derivatives (no unit's report does): d/dy' is not included.
#pragma once
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow {

struct OutputSensitivityOptions {
  double rel_step = 1e-6;  // relative step of the central differences, > 0 and < 0.1
  void validate() const;
};

// Row-major [time][param][output] over all outputs (SimResult::output_names) and the parameters of
// `result.sens_params`. `result` must come from simulate(fs, ...) with those sensitivities, on `fs` with the
// same parameter values. Throws ConfigError if the result carries no sensitivities.
std::vector<double> output_sensitivities(Flowsheet& fs, const SimResult& result,
                                         const OutputSensitivityOptions& options = {});

}  // namespace granuflow
