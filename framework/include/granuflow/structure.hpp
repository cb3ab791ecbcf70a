// Whether the algebraic equations of a flowsheet can determine its algebraic states, checked before a run so
// that a flowsheet that cannot be initialized is refused with the units and states at fault named, instead of
// failing inside consistent initialization (IDACalcIC) with a residual that points elsewhere.
//
// Consistent initialization solves the algebraic equations F_a(y_d, y_a) = 0 for the algebraic states y_a at
// given differential states y_d; its Newton matrix is block triangular with the block dF_a/dy_a, which must be
// nonsingular (an index-1 DAE). Two checks:
//  1. Structural: a perfect matching of algebraic equations to algebraic states on the Jacobian's sparsity
//     pattern (Hopcroft & Karp, SIAM J. Comput. 2 (1973) 225). Without one, no values of the parameters make
//     the block nonsingular; the unmatched part is named by the Dulmage-Mendelsohn decomposition (states that
//     no equation determines, equations that over-determine their states).
//  2. Numerical, at the initial state the units propose: the equilibrated block's rank (full-pivoting LU). A
//     recycle of algebraic units without hold-up (a mixer feeding a splitter feeding the mixer back) has a
//     full pattern but its mixing equations are singular there: the loop's states are named.
#pragma once
#include <vector>

#include "granuflow/dae_system.hpp"

namespace granuflow {

// Maximum matching of rows to columns of a bipartite graph given as, per row, the columns it contains.
struct Matching {
  std::vector<int> row_col;  // matched column of each row, or -1
  std::vector<int> col_row;  // matched row of each column, or -1
  int size = 0;
};
Matching maximum_matching(int n_cols, const std::vector<std::vector<int>>& row_cols);

// The structurally singular part (Dulmage-Mendelsohn): columns reachable from an unmatched column by
// alternating paths (under-determined) and rows reachable from an unmatched row (over-determined). Both
// empty if the matching is perfect.
struct Deficiency {
  std::vector<int> rows, cols;
};
Deficiency structural_deficiency(int n_cols, const std::vector<std::vector<int>>& row_cols, const Matching& m);

// Both checks on the system a run is about to integrate (its units configured with the run's parameters);
// throws ConfigError naming the flowsheet, the units and the states (at most 12) otherwise. Systems with more
// than 3000 algebraic states skip the numerical check (its dense factorization would cost more than it saves).
// `j0`: for an inlined system, its dense Jacobian dF/dy (cj = 0) at the initial values with y' = 0, when the caller
// has it (the run's consistent start needs the same matrix).
void check_algebraic_structure(DaeSystem& sys, const double* j0 = nullptr);

}  // namespace granuflow
