// The SUNDIALS glue our matrix-based direct linear solvers share (eigen_linear_solver, banded_lowrank_solver): a
// custom SUNLinearSolver that owns its Content (which keeps `last_flag`) and runs the solver's own setup and solve.
#pragma once

#include <sundials/sundials_linearsolver.h>

#include <memory>

namespace granuflow::detail {

template <class Content>
Content* direct_content(SUNLinearSolver s) {
  return static_cast<Content*>(s->content);
}

template <class Content>
SUNLinearSolver new_direct_solver(SUNContext ctx, std::unique_ptr<Content> content,
                                  int (*setup)(SUNLinearSolver, SUNMatrix),
                                  int (*solve)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, realtype)) {
  SUNLinearSolver s = SUNLinSolNewEmpty(ctx);
  if (!s) return nullptr;
  s->content = content.release();
  s->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  s->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  s->ops->initialize = [](SUNLinearSolver) { return 0; };
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->lastflag = [](SUNLinearSolver ls) -> sunindextype { return direct_content<Content>(ls)->last_flag; };
  s->ops->free = [](SUNLinearSolver ls) {
    if (!ls) return 0;
    delete direct_content<Content>(ls);
    ls->content = nullptr;
    SUNLinSolFreeEmpty(ls);
    return 0;
  };
  return s;
}

}  // namespace granuflow::detail
