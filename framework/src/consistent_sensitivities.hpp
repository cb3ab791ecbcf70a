// Consistent initial sensitivities of the index-1 DAE F(t, y, y', p) = 0 at a consistent (t, y, y').
// Differentiating F along p_k gives the linear system
//
//   F_y s_k + F_y' s'_k + F_p e_k = 0,
//
// solved for s_k of the algebraic states and s'_k of the differential ones (s_k of the differential states is
// given; s'_k of algebraic states is set to 0), with the matrix [F_y(:, algebraic) | F_y'(:, differential)]
// assembled from the exact Jacobian (F_y = J(cj = 0), F_y' = J(1) - J(0)) and factorized once for all
// parameters. simulate() uses it instead of IDACalcIC's sensitivity Newton, whose line search fails at many
// operating points of the headline scene (scaled residuals of order 1e6 that the full Newton step of this
// linear system removes exactly).
#pragma once
#include <vector>

#include "granuflow/dae_system.hpp"

namespace granuflow::detail {

// `dense`: the system's Jacobian is dense (DaeSystem::size() x size()), else in DaeSystem::pattern() order.
// yS, ypS: per parameter, arrays of DaeSystem::size(); yS's differential entries are read, the rest written.
void consistent_sensitivities(DaeSystem& sys, bool dense, double t, const double* y, const double* yp,
                              const std::vector<int>& params, double* const* yS, double* const* ypS);

}  // namespace granuflow::detail
