// The dense Jacobian a run keeps between integrator steps, and the residual contract that makes keeping it valid.
#pragma once
#include <vector>

#include "granuflow/dae_system.hpp"

namespace granuflow::detail {

// A dense Jacobian kept for reuse, the way CVODE keeps df/dy: IDA sets its Newton matrix up again whenever
// cj = alpha / h moves by 25 %, and with every differential state's residual of the form y'_k - f(y) (all
// units' contract, checked on the first evaluation of a run) only the diagonal of the differential states
// depends on cj. An evaluation at most max_age steps old is reused with cj updated, unless Newton (of the states
// or of their sensitivities) has failed to converge since; IDACalcIC and each segment start from a fresh one.
struct JacobianCache {
  long max_age = 20;  // Ida::tune_refactoring() raises it for large blocks
  // The Newton matrix's storage still holds the kept Jacobian everywhere but on the differential diagonal, where a
  // reuse writes diag + (cj - cj_kept): copying all n^2 entries out and back cost about 4 % of the two-zone scene at
  // 200 classes (600 unknowns), and the result is the same to the bit.
  const double* held = nullptr;   // that storage (a fresh evaluation not kept clears it)
  std::vector<double> diag;       // the kept Jacobian's differential diagonal, in the order of `differential`
  std::vector<int> differential;  // indices of the differential states
  double cj = 0.0;
  long step = 0, conv_fails = 0;
  bool valid = false;
  int reusable = -1;  // -1 unknown (checked on the first evaluation), 0 no, 1 yes
  // Keeps `a` (column-major n x n, evaluated at cj_at; it must not be written but by reuse) for reuse from
  // integrator step step_at on.
  void keep(const double* a, int n, double cj_at, long step_at, long fails_at);
};
// Sets k.reusable (and k.differential): dF/dy' must be the identity on the differential states and zero elsewhere.
// Checked along one direction v of y' (every component nonzero, pseudo-random): F(y, y' + v) - F(y, y') must be v on
// the differential rows and 0 on the algebraic ones. A residual that reads y' other than as the contract allows moves
// along almost every direction; the check costs one residual, where comparing two Jacobians cost one Jacobian.
void check_contract(DaeSystem& sys, double t, const double* y, const double* yp, JacobianCache& k);

}  // namespace granuflow::detail
