// Sensitivities of reported outputs (Unit::report, e.g. bed.d50) with respect to parameters:
//
//   dz_j/dp_k (t) = (d report_j / d y)(y(t), p) s_k(t) + (d report_j / d p_k)(y(t), p),
//
// where s_k = dy/dp_k are the IDAS forward sensitivities of all states (and quadratures). Units write report() as a
// template on the scalar type, so simulate() evaluates it with Jets that carry s_k and the parameter directions:
// both terms are exact, computed at every output time (SimResult::output_sens). Characteristic diameters (d10 ...
// d95) are piecewise smooth in the class masses (the cumulative distribution is interpolated between class edges):
// at a kink the derivative is the one-sided slope of the interval the value lies in.
// Contract: report() must not read state derivatives (no unit's report does): d/dy' is not included.
#pragma once
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow {

// Row-major [time][param][output] over all outputs (SimResult::output_names) and the parameters of
// `result.sens_params`. `result` must come from simulate(fs, ...) with those sensitivities. Throws ConfigError if
// the result carries no sensitivities or belongs to another flowsheet.
std::vector<double> output_sensitivities(const Flowsheet& fs, const SimResult& result);

}  // namespace granuflow
