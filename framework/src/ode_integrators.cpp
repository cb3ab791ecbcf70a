#include "ode_integrators.hpp"

#include <arkode/arkode_erkstep.h>
#include <cvodes/cvodes.h>
#include <cvodes/cvodes_ls.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cstdlib>

#include "granuflow/interrupt.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

namespace {

template <class F>
int guarded(OdeUser* u, F&& f) {
  if (interrupt_requested(u->interrupt_calls)) return -1;  // the run then ends with Interrupted (simulator.cpp)
  try {
    return static_cast<int>(f());
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ode_rhs(realtype t, N_Vector y, N_Vector ydot, void* ud) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] { return u->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)); });
}

// ARKODE's explicit methods have no quadratures: the integrals of flows ride along as extra components.
int erk_rhs(realtype t, N_Vector y, N_Vector ydot, void* ud) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    double* yy = N_VGetArrayPointer(y);
    double* yd = N_VGetArrayPointer(ydot);
    Status s = u->rhs(t, yy, yd);
    if (s == Status::kOk && u->nq > 0) s = u->sys->quadrature(t, yy, yd, yd + u->n);
    return s;
  });
}

int cv_jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* ud, N_Vector, N_Vector, N_Vector) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    const double *yy = N_VGetArrayPointer(y), *yp = N_VGetArrayPointer(fy);
    if (u->dense) {
      double* a = SUNDenseMatrix_Data(J);
      u->sys->jacobian(t, yy, yp, 0.0, a, nullptr);
      for (size_t k = 0, m = size_t(u->n) * u->n; k < m; ++k) a[k] = -a[k];
    } else {
      const auto& pat = u->sys->pattern();
      set_sparse_pattern(pat, J);
      double* v = SUNSparseMatrix_Data(J);
      u->sys->jacobian(t, yy, yp, 0.0, nullptr, v);
      for (int k = 0; k < pat.nnz(); ++k) v[k] = -v[k];
    }
    return Status::kOk;
  });
}

// CVODE's Newton matrix is I - gamma df/dy = gamma (cj I + dF/dy) with cj = 1 / gamma, F = y' - f: the DAE
// preconditioner of DaeSystem at cj, its solution scaled by 1 / gamma.
int cv_psetup(realtype t, N_Vector y, N_Vector, booleantype, booleantype* jcur, realtype gamma, void* ud) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    u->sys->precondition_setup(t, N_VGetArrayPointer(y), u->zeros.data(), 1.0 / gamma);
    *jcur = SUNTRUE;
    return Status::kOk;
  });
}

int cv_psolve(realtype t, N_Vector y, N_Vector, N_Vector r, N_Vector z, realtype gamma, realtype, int, void* ud) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    double* zz = N_VGetArrayPointer(z);
    u->sys->precondition_solve(t, N_VGetArrayPointer(y), u->zeros.data(), 1.0 / gamma, N_VGetArrayPointer(r), zz);
    for (int i = 0; i < u->n; ++i) zz[i] /= gamma;
    return Status::kOk;
  });
}

int cv_quad(realtype t, N_Vector y, N_Vector qdot, void* ud) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    const double* yy = N_VGetArrayPointer(y);
    u->f.resize(u->n);
    Status s = u->rhs(t, yy, u->f.data());
    if (s == Status::kOk) s = u->sys->quadrature(t, yy, u->f.data(), N_VGetArrayPointer(qdot));
    return s;
  });
}

// s' = (df/dy) s + df/dp = -(F_y s + F_p): the sensitivity residual with s' = 0, negated.
int cv_sens_rhs(int ns, realtype t, N_Vector y, N_Vector ydot, N_Vector* yS, N_Vector* ySdot, void* ud, N_Vector,
                N_Vector) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    u->yS.resize(ns), u->ypS.assign(ns, u->zeros.data()), u->rS.resize(ns);
    for (int k = 0; k < ns; ++k) u->yS[k] = N_VGetArrayPointer(yS[k]), u->rS[k] = N_VGetArrayPointer(ySdot[k]);
    const Status s = u->sys->sens_residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), u->params, u->yS.data(),
                                           u->ypS.data(), u->rS.data());
    for (int k = 0; k < ns; ++k)
      for (int i = 0; i < u->n; ++i) u->rS[k][i] = -u->rS[k][i];
    return s;
  });
}

int cv_quad_sens(int ns, realtype t, N_Vector y, N_Vector* yS, N_Vector, N_Vector* qSdot, void* ud, N_Vector,
                 N_Vector) {
  auto* u = static_cast<OdeUser*>(ud);
  return guarded(u, [&] {
    const double* yy = N_VGetArrayPointer(y);
    u->f.resize(u->n);
    Status s = u->rhs(t, yy, u->f.data());
    u->yS.resize(ns), u->qS.resize(ns);
    for (int k = 0; k < ns; ++k) u->yS[k] = N_VGetArrayPointer(yS[k]), u->qS[k] = N_VGetArrayPointer(qSdot[k]);
    if (s == Status::kOk) s = u->sys->quadrature_sens(t, yy, u->f.data(), u->params, u->yS.data(), u->qS.data());
    return s;
  });
}

void ode_err(int code, const char* module, const char* function, char* msg, void* ud) {
  if (code >= 0) return;
  static_cast<OdeUser*>(ud)->last_error = std::string(module) + "." + function + ": " + msg;
}

// The integrator's current time, y' there and its error weights (the first n of n_vec components).
template <class Time, class Dky, class Weights>
double last_state(void* mem, SUNContext ctx, int n_vec, int n, Time time, Dky dky, Weights weights_of, double* yp,
                  double* weights) {
  realtype t = 0;
  time(mem, &t);
  NVec d(n_vec, ctx), w(n_vec, ctx);
  dky(mem, t, 1, d.v);
  weights_of(mem, w.v);
  std::copy(d.data(), d.data() + n, yp);
  std::copy(w.data(), w.data() + n, weights);
  return t;
}

class Cvode : public OdeIntegrator {
 public:
  Cvode(SUNContext ctx, OdeUser& u, bool bdf, const SimOptions& opt, double t0, const double* y0,
        const std::vector<double>& atol, const std::vector<double>& qatol, long max_steps)
      : u_(u),
        ctx_(ctx),
        bdf_(bdf),
        y_(u.n, ctx),
        atol_(u.n, ctx),
        q_(std::max(u.nq, 1), ctx),
        qatol_(std::max(u.nq, 1), ctx) {
    std::copy(y0, y0 + u.n, y_.data());
    std::copy(atol.begin(), atol.end(), atol_.data());
    mem_ = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, ctx);
    check(CVodeInit(mem_, ode_rhs, t0, y_.v), "CVodeInit");
    check(CVodeSVtolerances(mem_, opt.rtol, atol_.v), "CVodeSVtolerances");
    check(CVodeSetUserData(mem_, &u), "CVodeSetUserData");
    check(CVodeSetErrHandlerFn(mem_, ode_err, &u), "CVodeSetErrHandlerFn");
    check(CVodeSetMaxNumSteps(mem_, max_steps), "CVodeSetMaxNumSteps");
    if (opt.max_step > 0) check(CVodeSetMaxStep(mem_, opt.max_step), "CVodeSetMaxStep");
    if (bdf && u.gmres) {
      LS_.s = SUNLinSol_SPGMR(y_.v, SUN_PREC_LEFT, kGmresMaxKrylov, ctx);
      check(CVodeSetLinearSolver(mem_, LS_.s, nullptr), "CVodeSetLinearSolver");
      check(CVodeSetPreconditioner(mem_, cv_psetup, cv_psolve), "CVodeSetPreconditioner");
    } else if (bdf) {
      make_linear_solver(u.dense, *u.sys, y_.v, ctx, A_, LS_);
      check(CVodeSetLinearSolver(mem_, LS_.s, A_.m), "CVodeSetLinearSolver");
      check(CVodeSetJacFn(mem_, cv_jac), "CVodeSetJacFn");
    } else {
      nls_ = SUNNonlinSol_FixedPoint(y_.v, 0, ctx);
      check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
    }
    if (u.nq > 0) {
      std::copy(qatol.begin(), qatol.end(), qatol_.data());
      check(CVodeQuadInit(mem_, cv_quad, q_.v), "CVodeQuadInit");
      check(CVodeQuadSVtolerances(mem_, opt.rtol, qatol_.v), "CVodeQuadSVtolerances");
      check(CVodeSetQuadErrCon(mem_, SUNTRUE), "CVodeSetQuadErrCon");
    }
    ns_ = static_cast<int>(u.params.size());
    if (ns_ > 0) {
      yS_ = N_VCloneVectorArray(ns_, y_.v);
      for (int k = 0; k < ns_; ++k) N_VConst(0.0, yS_[k]);
      check(CVodeSensInit(mem_, ns_, CV_STAGGERED, cv_sens_rhs, yS_), "CVodeSensInit");
      check(CVodeSensEEtolerances(mem_), "CVodeSensEEtolerances");
      check(CVodeSetSensErrCon(mem_, opt.sens_error_control ? SUNTRUE : SUNFALSE), "CVodeSetSensErrCon");
      if (!bdf) {
        nls_sens_ = SUNNonlinSol_FixedPointSens(ns_, y_.v, 0, ctx);
        check(CVodeSetNonlinearSolverSensStg(mem_, nls_sens_), "CVodeSetNonlinearSolverSensStg");
      }
      if (u.nq > 0) {
        qS_ = N_VCloneVectorArray(ns_, q_.v);
        for (int k = 0; k < ns_; ++k) N_VConst(0.0, qS_[k]);
        check(CVodeQuadSensInit(mem_, cv_quad_sens, qS_), "CVodeQuadSensInit");
        check(CVodeQuadSensEEtolerances(mem_), "CVodeQuadSensEEtolerances");
        check(CVodeSetQuadSensErrCon(mem_, opt.sens_error_control ? SUNTRUE : SUNFALSE), "CVodeSetQuadSensErrCon");
      }
    }
  }
  ~Cvode() override {
    if (yS_) N_VDestroyVectorArray(yS_, ns_);
    if (qS_) N_VDestroyVectorArray(qS_, ns_);
    CVodeFree(&mem_);
    if (nls_) SUNNonlinSolFree(nls_);
    if (nls_sens_) SUNNonlinSolFree(nls_sens_);
  }
  void restart(double t, const double* y, const double* q, const std::vector<std::vector<double>>& yS,
               const std::vector<std::vector<double>>& qS) override {
    bank_counts();
    std::copy(y, y + u_.n, y_.data());
    check(CVodeReInit(mem_, t, y_.v), "CVodeReInit");
    if (u_.nq > 0) {
      std::copy(q, q + u_.nq, q_.data());
      check(CVodeQuadReInit(mem_, q_.v), "CVodeQuadReInit");
    }
    if (ns_ > 0) {
      for (int k = 0; k < ns_; ++k) std::copy(yS[k].begin(), yS[k].end(), N_VGetArrayPointer(yS_[k]));
      check(CVodeSensReInit(mem_, CV_STAGGERED, yS_), "CVodeSensReInit");
      if (u_.nq > 0) {
        for (int k = 0; k < ns_; ++k) std::copy(qS[k].begin(), qS[k].end(), N_VGetArrayPointer(qS_[k]));
        check(CVodeQuadSensReInit(mem_, qS_), "CVodeQuadSensReInit");
      }
    }
  }
  void set_stop(double t) override { check(CVodeSetStopTime(mem_, t), "CVodeSetStopTime"); }
  int advance(double tout, double* y, double* t) override {
    realtype tret = *t;
    const int flag = CVode(mem_, tout, y_.v, &tret, CV_NORMAL);
    std::copy(y_.data(), y_.data() + u_.n, y);
    *t = tret;
    return flag;
  }
  void quadratures(double t, double* q) override {
    if (u_.nq == 0) return;
    realtype tret = t;
    check(CVodeGetQuad(mem_, &tret, q_.v), "CVodeGetQuad");
    std::copy(q_.data(), q_.data() + u_.nq, q);
  }
  void sensitivities(double t, std::vector<std::vector<double>>& yS, std::vector<std::vector<double>>& qS) override {
    realtype tret = t;
    check(CVodeGetSens(mem_, &tret, yS_), "CVodeGetSens");
    for (int k = 0; k < ns_; ++k) yS[k].assign(N_VGetArrayPointer(yS_[k]), N_VGetArrayPointer(yS_[k]) + u_.n);
    if (u_.nq > 0) {
      check(CVodeGetQuadSens(mem_, &tret, qS_), "CVodeGetQuadSens");
      for (int k = 0; k < ns_; ++k) qS[k].assign(N_VGetArrayPointer(qS_[k]), N_VGetArrayPointer(qS_[k]) + u_.nq);
    }
  }
  std::string flag_text(int flag) const override { return flag_name(CVodeGetReturnFlagName(flag), "CVODE error"); }
  bool too_much_work(int flag) const override { return flag == CV_TOO_MUCH_WORK; }
  double failed_state(double* yp, double* weights) const override {
    return last_state(mem_, ctx_, u_.n, u_.n, CVodeGetCurrentTime, CVodeGetDky, CVodeGetErrWeights, yp, weights);
  }

 private:
  void add_current(SolverStats& s) const override {
    long v = 0;
    CVodeGetNumSteps(mem_, &v), s.steps += v;
    if (bdf_) CVodeGetNumLinSolvSetups(mem_, &v), s.linear_setups += v;
    CVodeGetNumNonlinSolvIters(mem_, &v), s.nonlinear_iterations += v;
    CVodeGetNumErrTestFails(mem_, &v), s.error_test_failures += v;
    CVodeGetNumNonlinSolvConvFails(mem_, &v), s.nonlinear_failures += v;
    if (bdf_ && u_.gmres) {
      CVodeGetNumLinIters(mem_, &v), s.linear_iterations += v;
      CVodeGetNumPrecEvals(mem_, &v), s.preconditioner_setups += v;
      CVodeGetNumLinConvFails(mem_, &v), s.linear_failures += v;
    }
  }

  OdeUser& u_;
  SUNContext ctx_;
  bool bdf_;
  NVec y_, atol_, q_, qatol_;
  void* mem_ = nullptr;
  Mat A_;
  LinSol LS_;
  SUNNonlinearSolver nls_ = nullptr, nls_sens_ = nullptr;
  int ns_ = 0;
  N_Vector* yS_ = nullptr;
  N_Vector* qS_ = nullptr;
};

// Dormand-Prince 5(4) with ARKODE's adaptive step; quadratures appended to the state.
class Erk : public OdeIntegrator {
 public:
  Erk(SUNContext ctx, OdeUser& u, const SimOptions& opt, double t0, const double* y0, const std::vector<double>& atol,
      const std::vector<double>& qatol, long max_steps)
      : u_(u), ctx_(ctx), y_(u.n + u.nq, ctx), atol_(u.n + u.nq, ctx) {
    std::copy(y0, y0 + u.n, y_.data());
    std::copy(atol.begin(), atol.end(), atol_.data());
    std::copy(qatol.begin(), qatol.begin() + u.nq, atol_.data() + u.n);
    mem_ = ERKStepCreate(erk_rhs, t0, y_.v, ctx);
    check(ERKStepSVtolerances(mem_, opt.rtol, atol_.v), "ERKStepSVtolerances");
    check(ERKStepSetTableNum(mem_, ARKODE_DORMAND_PRINCE_7_4_5), "ERKStepSetTableNum");
    check(ERKStepSetUserData(mem_, &u), "ERKStepSetUserData");
    check(ERKStepSetErrHandlerFn(mem_, ode_err, &u), "ERKStepSetErrHandlerFn");
    check(ERKStepSetMaxNumSteps(mem_, max_steps), "ERKStepSetMaxNumSteps");
    if (opt.max_step > 0) check(ERKStepSetMaxStep(mem_, opt.max_step), "ERKStepSetMaxStep");
  }
  ~Erk() override { ERKStepFree(&mem_); }
  void restart(double t, const double* y, const double* q, const std::vector<std::vector<double>>&,
               const std::vector<std::vector<double>>&) override {
    bank_counts();
    std::copy(y, y + u_.n, y_.data());
    if (u_.nq > 0) std::copy(q, q + u_.nq, y_.data() + u_.n);
    check(ERKStepReInit(mem_, erk_rhs, t, y_.v), "ERKStepReInit");
  }
  void set_stop(double t) override { check(ERKStepSetStopTime(mem_, t), "ERKStepSetStopTime"); }
  int advance(double tout, double* y, double* t) override {
    realtype tret = *t;
    const int flag = ERKStepEvolve(mem_, tout, y_.v, &tret, ARK_NORMAL);
    std::copy(y_.data(), y_.data() + u_.n, y);
    *t = tret;
    return flag;
  }
  void quadratures(double, double* q) override { std::copy(y_.data() + u_.n, y_.data() + u_.n + u_.nq, q); }
  void sensitivities(double, std::vector<std::vector<double>>&, std::vector<std::vector<double>>&) override {}
  std::string flag_text(int flag) const override { return flag_name(ERKStepGetReturnFlagName(flag), "ARKODE error"); }
  bool too_much_work(int flag) const override { return flag == ARK_TOO_MUCH_WORK; }
  double failed_state(double* yp, double* weights) const override {
    return last_state(mem_, ctx_, u_.n + u_.nq, u_.n, ERKStepGetCurrentTime, ERKStepGetDky, ERKStepGetErrWeights, yp,
                      weights);
  }

 private:
  void add_current(SolverStats& s) const override {
    long v = 0;
    ERKStepGetNumSteps(mem_, &v), s.steps += v;
    ERKStepGetNumErrTestFails(mem_, &v), s.error_test_failures += v;
  }

  OdeUser& u_;
  SUNContext ctx_;
  NVec y_, atol_;
  void* mem_ = nullptr;
};

}  // namespace

std::unique_ptr<OdeIntegrator> make_cvode(SUNContext ctx, OdeUser& u, bool bdf, const SimOptions& opt, double t0,
                                          const double* y0, const std::vector<double>& atol,
                                          const std::vector<double>& qatol, long max_steps) {
  return std::make_unique<Cvode>(ctx, u, bdf, opt, t0, y0, atol, qatol, max_steps);
}

std::unique_ptr<OdeIntegrator> make_erk(SUNContext ctx, OdeUser& u, const SimOptions& opt, double t0, const double* y0,
                                        const std::vector<double>& atol, const std::vector<double>& qatol,
                                        long max_steps) {
  return std::make_unique<Erk>(ctx, u, opt, t0, y0, atol, qatol, max_steps);
}

}  // namespace granuflow::detail
