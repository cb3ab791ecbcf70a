#include "ode_simulator.hpp"

#include <arkode/arkode_erkstep.h>
#include <cvodes/cvodes.h>
#include <cvodes/cvodes_ls.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "granuflow/errors.hpp"
#include "run_common.hpp"
#include "solver_setup.hpp"

namespace granuflow::detail {

std::string first_algebraic_state(const Flowsheet& fs) {
  for (int i = 0; i < fs.n_states() - fs.n_explicit_states(); ++i)
    if (fs.state_spec(i).kind == StateKind::Algebraic)
      return "unit '" + fs.units()[fs.state_unit(i)].name + "', state '" + fs.state_spec(i).name + "'";
  return "";
}

namespace {

// f(t, y) = -F(t, y, 0) and what the SUNDIALS callbacks need around it.
struct OdeUser {
  DaeSystem* sys = nullptr;
  bool dense = true;
  bool gmres = false;  // BDF's Newton systems by GMRES with the units' preconditioners (solver_setup.hpp)
  int n = 0, nq = 0;
  std::vector<int> params;
  std::vector<double> zeros, f, r;
  std::vector<const double*> yS, ypS;
  std::vector<double*> rS, qS;
  std::string last_error;

  Status rhs(double t, const double* y, double* ydot) {
    const Status s = sys->residual(t, y, zeros.data(), ydot);
    for (int i = 0; i < n; ++i) ydot[i] = -ydot[i];
    return s;
  }
};

template <class F>
int guarded(OdeUser* u, F&& f) {
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

// One integrator behind the run loop, so that auto can hand a run from a non-stiff method to BDF mid-way.
class Stepper {
 public:
  virtual ~Stepper() = default;
  // Restart at t from y (and q, sensitivities): a segment start, or the state handed over by another stepper.
  virtual void restart(double t, const double* y, const double* q, const std::vector<std::vector<double>>& yS,
                       const std::vector<std::vector<double>>& qS) = 0;
  virtual void set_stop(double t) = 0;
  // Advances towards tout; returns the flag (< 0 failure) with y and t where it stopped.
  virtual int advance(double tout, double* y, double* t) = 0;
  virtual void quadratures(double t, double* q) = 0;
  virtual void sensitivities(double t, std::vector<std::vector<double>>& yS, std::vector<std::vector<double>>& qS) = 0;
  virtual long steps() const = 0;
  virtual void add_stats(SolverStats& s) const = 0;
  virtual std::string flag_text(int flag) const = 0;
  virtual bool too_much_work(int flag) const = 0;
};

class Cvode : public Stepper {
 public:
  Cvode(SUNContext ctx, OdeUser& u, bool bdf, const SimOptions& opt, double t0, const double* y0,
        const std::vector<double>& atol, const std::vector<double>& qatol, long max_steps)
      : u_(u), bdf_(bdf), y_(u.n, ctx), atol_(u.n, ctx), q_(std::max(u.nq, 1), ctx), qatol_(std::max(u.nq, 1), ctx) {
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
    add_counts();
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
  long steps() const override {
    long v = 0;
    CVodeGetNumSteps(mem_, &v);
    return v + done_.steps;
  }
  void add_stats(SolverStats& s) const override {
    SolverStats c = done_;
    add_current(c);
    s.steps += c.steps, s.linear_setups += c.linear_setups, s.nonlinear_iterations += c.nonlinear_iterations;
    s.error_test_failures += c.error_test_failures, s.nonlinear_failures += c.nonlinear_failures;
    s.linear_iterations += c.linear_iterations, s.preconditioner_setups += c.preconditioner_setups;
    s.linear_failures += c.linear_failures;
  }
  std::string flag_text(int flag) const override {
    char* name = CVodeGetReturnFlagName(flag);
    std::string s = name ? name : "CVODE error";
    free(name);
    return s;
  }
  bool too_much_work(int flag) const override { return flag == CV_TOO_MUCH_WORK; }

 private:
  // CVodeReInit zeroes the counters: keep what each stretch did.
  void add_current(SolverStats& s) const {
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
  void add_counts() { add_current(done_); }

  OdeUser& u_;
  bool bdf_;
  NVec y_, atol_, q_, qatol_;
  void* mem_ = nullptr;
  Mat A_;
  LinSol LS_;
  SUNNonlinearSolver nls_ = nullptr, nls_sens_ = nullptr;
  int ns_ = 0;
  N_Vector* yS_ = nullptr;
  N_Vector* qS_ = nullptr;
  SolverStats done_;
};

// Dormand-Prince 5(4) with ARKODE's adaptive step; quadratures appended to the state.
class Erk : public Stepper {
 public:
  Erk(SUNContext ctx, OdeUser& u, const SimOptions& opt, double t0, const double* y0, const std::vector<double>& atol,
      const std::vector<double>& qatol, long max_steps)
      : u_(u), y_(u.n + u.nq, ctx), atol_(u.n + u.nq, ctx) {
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
    add_counts();
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
  long steps() const override {
    long v = 0;
    ERKStepGetNumSteps(mem_, &v);
    return v + done_.steps;
  }
  void add_stats(SolverStats& s) const override {
    SolverStats c = done_;
    add_current(c);
    s.steps += c.steps, s.error_test_failures += c.error_test_failures;
  }
  std::string flag_text(int flag) const override {
    char* name = ERKStepGetReturnFlagName(flag);
    std::string s = name ? name : "ARKODE error";
    free(name);
    return s;
  }
  bool too_much_work(int flag) const override { return flag == ARK_TOO_MUCH_WORK; }

 private:
  void add_current(SolverStats& s) const {
    long v = 0;
    ERKStepGetNumSteps(mem_, &v), s.steps += v;
    ERKStepGetNumErrTestFails(mem_, &v), s.error_test_failures += v;
  }
  void add_counts() { add_current(done_); }

  OdeUser& u_;
  NVec y_, atol_;
  void* mem_ = nullptr;
  SolverStats done_;
};

// The residual must be y' - f(y): F(y0, v) - F(y0, 0) = v for a generic v.
void check_ode_form(DaeSystem& sys, double t, const std::vector<double>& y) {
  const int n = sys.size();
  std::vector<double> v(n), r0(n), r1(n), zeros(n, 0.0);
  for (int i = 0; i < n; ++i) v[i] = 1.0 + 0.37 * (i % 7);
  sys.residual(t, y.data(), zeros.data(), r0.data());
  sys.residual(t, y.data(), v.data(), r1.data());
  for (int i = 0; i < n; ++i)
    if (std::abs(r1[i] - r0[i] - v[i]) > 1e-9 * (v[i] + std::abs(r0[i])))
      throw NotAnOde("the residual of " + sys.describe_row(i) + " is not of the form y' - f(y)");
}

// Largest |eigenvalue| of df/dy at (t, y) by power iteration on difference quotients of f (no Jacobian: the
// estimate only has to be right within a factor of a few).
double spectral_radius(OdeUser& u, double t, const std::vector<double>& y, const std::vector<double>& scale) {
  const int n = u.n;
  std::vector<double> f0(n), f1(n), v(n), yy(n);
  u.rhs(t, y.data(), f0.data());
  for (int i = 0; i < n; ++i) v[i] = scale[i] * (1.0 + 0.1 * (i % 5));
  double rho = 0.0;
  for (int it = 0; it < 12; ++it) {
    double nv = 0.0;
    for (int i = 0; i < n; ++i) nv = std::max(nv, std::abs(v[i]) / scale[i]);
    if (!(nv > 0.0) || !std::isfinite(nv)) break;
    const double eps = 1e-7 / nv;  // a step of 1e-7 of each state's scale
    for (int i = 0; i < n; ++i) yy[i] = y[i] + eps * v[i];
    u.rhs(t, yy.data(), f1.data());
    double nw = 0.0, nvv = 0.0;
    for (int i = 0; i < n; ++i) {
      v[i] = (f1[i] - f0[i]) / eps;
      nw += (v[i] / scale[i]) * (v[i] / scale[i]);
      nvv += (yy[i] - y[i]) / eps / scale[i] * ((yy[i] - y[i]) / eps / scale[i]);
    }
    if (!(nw > 0.0) || !std::isfinite(nw)) break;
    rho = std::sqrt(nw / nvv);
  }
  return rho;
}

// Dormand-Prince's stability interval on the negative real axis is about 3.3 step sizes; below this many steps
// for stability alone an explicit method wins over BDF's Jacobians and factorizations.
constexpr double kErkStability = 3.3;
constexpr double kErkStepBudget = 2000.0;

std::string describe(const std::string& method, bool gmres = false) {
  if (method == "bdf")
    return gmres ? "bdf (CVODES, Newton with GMRES)" : "bdf (CVODES, Newton with the exact Jacobian)";
  if (method == "adams") return "adams (CVODES, fixed-point iteration)";
  return "erk (ARKODE, Dormand-Prince 5(4))";
}

}  // namespace

SimResult simulate_ode(Flowsheet& fs, const SimOptions& opt, const std::string& requested) {
  const auto wall0 = std::chrono::steady_clock::now();
  // Explicit units are inlined (their states are no unknowns of an ODE); a Newton matrix over inlined units is the
  // dense Schur complement, so BDF on a system too large for dense algebra goes to IDAS instead.
  const LinearSolverKind kind = choose_linear_solver(fs, opt.linear_solver, opt.dense_limit);
  const bool dense = kind == LinearSolverKind::kDense, gmres = kind == LinearSolverKind::kGmres;
  if (requested == "bdf" && kind == LinearSolverKind::kSparse && fs.n_explicit_states() > 0)
    throw NotAnOde("BDF with sparse linear algebra needs the explicit units as unknowns");
  if (gmres && !opt.sensitivities.empty())
    throw ConfigError("sensitivities need a direct linear solver (solver.linear_solver: dense or sparse), not gmres");
  const std::shared_ptr<DaeSystem> held = fs.take_system(true);
  DaeSystem& sys = *held;
  const int n = sys.size(), nq = sys.n_quadratures();
  const std::vector<int> sens_ids = sensitivity_ids(fs, opt);
  const std::vector<double> t_out = output_times(opt);
  const int ns = static_cast<int>(sens_ids.size());
  if (requested == "erk" && ns > 0)
    throw ConfigError("solver.method = 'erk': ARKODE's explicit methods compute no sensitivities (" +
                      std::to_string(ns) + " asked for); use bdf, adams or ida");

  std::vector<double> y(n);
  {
    std::vector<double> y0;
    sys.initial_values(y0);
    std::copy(y0.begin(), y0.begin() + n, y.begin());
  }
  sys.set_segment_start(0.0);
  check_ode_form(sys, 0.0, y);

  OdeUser user;
  user.sys = &sys, user.dense = dense, user.gmres = gmres, user.n = n, user.nq = nq, user.params = sens_ids;
  user.zeros.assign(n, 0.0);
  const auto sc = sys.scales();

  std::string method = requested, reason;
  double predicted_steps = 0.0;
  if (requested == "auto") {
    const double rho = spectral_radius(user, 0.0, y, sc);
    predicted_steps = rho * opt.t_end / kErkStability;
    std::ostringstream os;
    os << "an ODE; spectral radius of df/dy at the start " << fmt_num(rho) << " 1/s over " << fmt_num(opt.t_end)
       << " s: about " << fmt_num(std::ceil(predicted_steps)) << " explicit steps for stability alone";
    if (predicted_steps <= kErkStepBudget) {
      method = ns > 0 ? "adams" : "erk";
      os << " (non-stiff" << (ns > 0 ? "; sensitivities asked for, so Adams rather than Runge-Kutta)" : ")");
    } else {
      method = "bdf";
      os << " (stiff)";
      if (kind == LinearSolverKind::kSparse && fs.n_explicit_states() > 0)
        throw NotAnOde(os.str() + ", too large for a dense Newton matrix");
    }
    reason = os.str();
  } else {
    reason = "asked for (solver.method)";
  }

  std::vector<double> atol(n), qatol(std::max(nq, 1), 1.0);
  for (int i = 0; i < n; ++i) atol[i] = opt.atol * sc[i];
  const auto qsc = sys.quadrature_scales();
  for (int i = 0; i < nq; ++i) qatol[i] = opt.atol * qsc[i];

  Context C;
  // A non-stiff method that auto chose gets a step budget per output interval; past it the run goes on with BDF.
  const bool may_switch = requested == "auto" && method != "bdf";
  const long budget = may_switch ? static_cast<long>(std::max(10.0 * predicted_steps, 5000.0)) : opt.max_steps;
  auto make = [&](const std::string& m, double t0, const double* y0) -> std::unique_ptr<Stepper> {
    const long steps = (may_switch && m != "bdf") ? std::min(budget, opt.max_steps) : opt.max_steps;
    if (m == "erk") return std::make_unique<Erk>(C.ctx, user, opt, t0, y0, atol, qatol, steps);
    return std::make_unique<Cvode>(C.ctx, user, m == "bdf", opt, t0, y0, atol, qatol, steps);
  };
  const std::string first = method;
  std::unique_ptr<Stepper> stepper = make(method, 0.0, y.data());
  std::vector<std::unique_ptr<Stepper>> retired;

  SimResult res;
  Recorder recorder(fs, sys, opt, sens_ids, res);
  res.stats.states = n;
  res.stats.explicit_states = sys.full_size() - n;
  res.stats.quadratures = nq;
  std::vector<double> q(std::max(nq, 1), 0.0), yp(n);
  std::vector<std::vector<double>> yS(ns, std::vector<double>(n)), qS(ns, std::vector<double>(std::max(nq, 1), 0.0));
  if (ns > 0) {
    std::vector<std::vector<double>> yS0;
    sys.initial_sensitivities(sens_ids, yS0);
    for (int k = 0; k < ns; ++k) std::copy(yS0[k].begin(), yS0[k].begin() + n, yS[k].begin());
    stepper->restart(0.0, y.data(), q.data(), yS, qS);  // the initial state's own sensitivities (d N0 / d v0 ...)
  }
  auto fail = [&](int flag, double t) {
    std::ostringstream os;
    os << "integration (" << method << ") failed at t = " << t << " s: " << stepper->flag_text(flag)
       << (user.last_error.empty() ? "" : " (" + user.last_error + ")");
    throw SolverError(os.str(), t, "", 0.0);
  };
  auto record = [&](double t) {
    if (t > 0) {
      stepper->quadratures(t, q.data());
      if (ns > 0) stepper->sensitivities(t, yS, qS);
    }
    user.rhs(t, y.data(), yp.data());
    std::vector<const double*> ys(ns), qs(ns);
    for (int k = 0; k < ns; ++k) ys[k] = yS[k].data(), qs[k] = qS[k].data();
    recorder.record(t, y.data(), yp.data(), nq > 0 ? q.data() : nullptr, ns > 0 ? ys.data() : nullptr,
                    ns > 0 && nq > 0 ? qs.data() : nullptr);
  };

  std::vector<double> ends = fs.breakpoints(opt.t_end);
  ends.push_back(opt.t_end);
  double t0 = 0.0;
  size_t iout = 0;
  for (size_t seg = 0; seg < ends.size(); ++seg) {
    const double t1 = ends[seg];
    sys.set_segment_start(t0);
    if (seg > 0) {
      stepper->restart(t0, y.data(), q.data(), yS, qS);
      ++res.stats.reinits;
    }
    while (iout < t_out.size() && t_out[iout] <= t0 + 1e-12 * std::max(1.0, t0)) {
      if (seg == 0) record(t_out[iout]);
      ++iout;
    }
    stepper->set_stop(t1);
    double t = t0;
    while (t < t1) {
      const bool to_output = iout < t_out.size() && t_out[iout] <= t1;
      const double target = to_output ? t_out[iout] : t1;
      int flag = stepper->advance(target, y.data(), &t);
      if (flag < 0 && may_switch && method != "bdf" && stepper->too_much_work(flag)) {
        // stiffness the start did not show: go on with BDF from here
        stepper->quadratures(t, q.data());
        if (ns > 0) stepper->sensitivities(t, yS, qS);
        std::ostringstream os;
        os << "; " << method << " needed more than " << budget << " steps before t = " << fmt_num(t)
           << " s (stiff there): bdf from then on";
        reason += os.str();
        stepper->add_stats(res.stats);
        retired.push_back(std::move(stepper));
        method = "bdf";
        stepper = make("bdf", t, y.data());
        stepper->restart(t, y.data(), q.data(), yS, qS);
        stepper->set_stop(t1);
        continue;
      }
      if (flag < 0) fail(flag, t);
      if (to_output && t >= t_out[iout] * (1 - 1e-14)) {
        record(t_out[iout]);
        ++iout;
      }
      if (t >= t1 * (1 - 1e-14)) break;
    }
    if (t1 > t0) stepper->quadratures(t1, q.data());
    if (ns > 0 && t1 > t0) stepper->sensitivities(t1, yS, qS);
    t0 = t1;
  }
  stepper->add_stats(res.stats);
  res.stats.method =
      retired.empty() ? describe(method, gmres) : describe(first, gmres) + ", then " + describe(method, gmres);
  res.stats.method_reason = reason;
  res.stats.linear_solver = method == "bdf" ? linear_solver_name(kind) : "none";
  res.stats.residuals = sys.residual_count();
  res.stats.jacobians = sys.jacobian_count();
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  sys.end_run();
  return res;
}

}  // namespace granuflow::detail
