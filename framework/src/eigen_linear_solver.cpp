#include "eigen_linear_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>

namespace granuflow::detail {
namespace {

struct Content {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  long last_flag = 0;
};

Content* content(SUNLinearSolver s) { return static_cast<Content*>(s->content); }

SUNLinearSolver_Type get_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID get_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int initialize(SUNLinearSolver) { return 0; }

int setup(SUNLinearSolver s, SUNMatrix a) {
  const auto n = SUNDenseMatrix_Rows(a);
  Eigen::Map<const Eigen::MatrixXd> m(SUNDenseMatrix_Data(a), n, n);  // column-major, like SUNDenseMatrix
  content(s)->lu.compute(m);
  // A zero or non-finite pivot makes the step fail recoverably: the integrator retries with a smaller step.
  // (A condition estimate would cost as much as a third of the factorization.)
  const auto diag = content(s)->lu.matrixLU().diagonal();
  content(s)->last_flag = (diag.allFinite() && diag.cwiseAbs().minCoeff() > 0.0) ? 0 : 1;
  return static_cast<int>(content(s)->last_flag);
}

int solve(SUNLinearSolver s, SUNMatrix a, N_Vector x, N_Vector b, realtype) {
  const auto n = SUNDenseMatrix_Rows(a);
  Eigen::Map<const Eigen::VectorXd> bv(N_VGetArrayPointer(b), n);
  Eigen::Map<Eigen::VectorXd> xv(N_VGetArrayPointer(x), n);
  xv = content(s)->lu.solve(bv);
  if (!xv.allFinite()) return content(s)->last_flag = 1;
  return content(s)->last_flag = 0;
}

sunindextype last_flag(SUNLinearSolver s) { return content(s)->last_flag; }

int free_solver(SUNLinearSolver s) {
  if (!s) return 0;
  delete content(s);
  s->content = nullptr;
  SUNLinSolFreeEmpty(s);
  return 0;
}

}  // namespace

SUNLinearSolver make_eigen_dense_solver(SUNContext ctx) {
  SUNLinearSolver s = SUNLinSolNewEmpty(ctx);
  if (!s) return nullptr;
  s->content = new Content();
  s->ops->gettype = get_type;
  s->ops->getid = get_id;
  s->ops->initialize = initialize;
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->lastflag = last_flag;
  s->ops->free = free_solver;
  return s;
}

}  // namespace granuflow::detail
