// A SUNDIALS direct linear solver backed by Eigen's blocked partial-pivoting LU on a SUNDenseMatrix.
// SUNDIALS' own dense LU is unblocked; at 100+ states it dominates the solve time.
#pragma once
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

namespace granuflow::detail {

SUNLinearSolver make_eigen_dense_solver(SUNContext ctx);

}  // namespace granuflow::detail
