// A SUNDIALS direct linear solver backed by Eigen's blocked partial-pivoting LU on a SUNDenseMatrix.
// SUNDIALS' own dense LU is unblocked; at 100+ states it dominates the solve time. A matrix whose nonzeros fall into
// independent groups of states (flowsheets that hold separate processes side by side, such as a two-zone bed beside
// a one-zone one) is factored group by group: the LU of blocks of sizes n_1 + n_2 costs n_1^3 + n_2^3, not (n_1 +
// n_2)^3.
#pragma once
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

namespace granuflow::detail {

SUNLinearSolver make_eigen_dense_solver(SUNContext ctx);
// The number of independent groups the last setup factored (1: the matrix as a whole, also when one group holds
// more than 90 % of the states).
int eigen_dense_groups(SUNLinearSolver s);
// The size of the largest matrix the last setup factored: the whole matrix, or its largest group (0 before any setup).
int eigen_dense_largest_block(SUNLinearSolver s);
// The size of the largest matrix a setup of the column-major n x n matrix `a` would factor, without factoring it.
int eigen_dense_block_for(const double* a, int n);

}  // namespace granuflow::detail
