// Consistent values (y, y') at the start of a segment for a dense run whose units keep the residual contract
// (a differential state's residual is y'_k - f_k(y), an algebraic one does not read y'; JacobianCache::reusable):
// Newton on the algebraic states alone, with their exact block dF_a/dy_a of the Jacobian at cj = 0, then
// y'_d = f_d(y) from one residual (exact: the residual is linear in y'_d with slope one).
//
// IDACalcIC's Newton matrix dF/dy + dF/dy' / h_ic is the exact one for neither of its unknown sets (it carries
// dF/dy of the differential columns), so its Newton converges linearly and asks for fresh Jacobians: 3 Jacobians and
// 16 residuals at the headline scene's start, 13 % of its run at 40 classes. Here the Newton is exact: that start
// now costs the one Jacobian the structural check evaluates anyway and 6 residuals.
#pragma once
#include "jacobian_cache.hpp"

namespace granuflow::detail {

// `ewt`: the integrator's error weights 1 / (rtol |y_i| + atol_i) at the given y. On success y and yp are consistent
// and the cache knows whether the contract holds (its Jacobian is left invalid); returns the size of the largest
// block the dense solver will factor (for Ida::tune_refactoring). Returns 0, y and yp untouched, when the contract does
// not hold, the algebraic block is singular or Newton does not converge: the caller falls back to IDACalcIC.
// `j0`, if given: the Jacobian dF/dy (cj = 0) at the given (t, y, y'), column-major n x n.
int consistent_start(DaeSystem& sys, JacobianCache& cache, double t, const double* ewt, double* y, double* yp,
                     const double* j0 = nullptr);

}  // namespace granuflow::detail
