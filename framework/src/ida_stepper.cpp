#include "ida_stepper.hpp"

#include <algorithm>
#include <cmath>

#include "banded_lowrank_solver.hpp"
#include "class_local_solver.hpp"
#include "consistent_sensitivities.hpp"
#include "consistent_start.hpp"
#include "granuflow/errors.hpp"

namespace granuflow::detail {

namespace {

int ida_sens_res(int ns, realtype t, N_Vector y, N_Vector yp, N_Vector, N_Vector* yS, N_Vector* ypS, N_Vector* rS,
                 void* ud, N_Vector, N_Vector, N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
  u->yS.resize(ns);
  u->ypS.resize(ns);
  u->rS.resize(ns);
  for (int k = 0; k < ns; ++k) {
    u->yS[k] = N_VGetArrayPointer(yS[k]);
    u->ypS[k] = N_VGetArrayPointer(ypS[k]);
    u->rS[k] = N_VGetArrayPointer(rS[k]);
  }
  try {
    return static_cast<int>(u->sys->sens_residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), u->sens_params,
                                                  u->yS.data(), u->ypS.data(), u->rS.data()));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_quad(realtype t, N_Vector y, N_Vector yp, N_Vector q, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    return static_cast<int>(
        u->sys->quadrature(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(q)));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_quad_sens(int ns, realtype t, N_Vector y, N_Vector yp, N_Vector* yS, N_Vector*, N_Vector, N_Vector* qS,
                  void* ud, N_Vector, N_Vector, N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
  u->yS.resize(ns);
  u->qS.resize(ns);
  for (int k = 0; k < ns; ++k) {
    u->yS[k] = N_VGetArrayPointer(yS[k]);
    u->qS[k] = N_VGetArrayPointer(qS[k]);
  }
  try {
    return static_cast<int>(u->sys->quadrature_sens(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), u->sens_params,
                                                    u->yS.data(), u->qS.data()));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_roots(realtype t, N_Vector y, N_Vector yp, realtype* g, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    return u->roots(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), g);
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

}  // namespace

IdaStepper::IdaStepper(DaeSystem& sys, const SimOptions& opt, LinearSolverKind kind, const std::vector<int>& sens_ids,
                       std::vector<double> j0, std::string reason)
    : sys_(sys),
      opt_(opt),
      kind_(kind),
      dense_(kind == LinearSolverKind::kDense || kind == LinearSolverKind::kBanded ||
             kind == LinearSolverKind::kClassLocal),
      sens_ids_(sens_ids),
      j0_(std::move(j0)),
      ewt_(sys.size()),
      reason_(std::move(reason)),
      n_(sys.size()),
      nq_(sys.n_quadratures()),
      ns_(static_cast<int>(sens_ids.size())),
      y_(n_, C_.ctx),
      yp_(n_, C_.ctx),
      atol_(n_, C_.ctx),
      q_(std::max(nq_, 1), C_.ctx),
      qatol_(std::max(nq_, 1), C_.ctx),
      user_(&sys, dense_, sens_ids),
      yS_now_(ns_),
      qS_now_(ns_) {
  std::vector<double> y0;
  sys.initial_values(y0);
  std::copy(y0.begin(), y0.end(), y_.data());
  const auto scales = sys.scales();
  for (int i = 0; i < n_; ++i) atol_.data()[i] = opt.atol * scales[i];
  user_.iterative = kind == LinearSolverKind::kGmres;
  user_.banded = kind == LinearSolverKind::kBanded;
  user_.class_local = kind == LinearSolverKind::kClassLocal;
  ida_ = std::make_unique<Ida>(C_.ctx, user_, 0.0, y_, yp_, opt.rtol, atol_);
  void* mem = ida_->mem;
  if (dense_) user_.mem = mem;
  // Algebraic states (and their sensitivities) follow the differential ones exactly; testing their local
  // error only makes the integrator stall at kinks of closures (floors, caps, the drying curve's knee).
  check(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg");
  check(IDASetMaxNumSteps(mem, opt.max_steps), "IDASetMaxNumSteps");
  if (opt.max_step > 0) check(IDASetMaxStep(mem, opt.max_step), "IDASetMaxStep");
  // Inventories declared non-negative: IDAS rejects a step that takes one below zero and retries it shorter, so a
  // rate that drains an inventory faster than it shrinks cannot overshoot into negative mass. A run that never
  // leaves the constraint takes exactly the steps it takes without it.
  if (const std::vector<double> c = sys.constraints(); !c.empty()) {
    constraints_ = std::make_unique<NVec>(n_, C_.ctx);
    std::copy(c.begin(), c.end(), constraints_->data());
    check(IDASetConstraints(mem, constraints_->v), "IDASetConstraints");
  }
  init_quadratures();
  init_sensitivities();
}

IdaStepper::~IdaStepper() {
  if (yS_) N_VDestroyVectorArray(yS_, ns_);
  if (ypS_) N_VDestroyVectorArray(ypS_, ns_);
  if (qS_) N_VDestroyVectorArray(qS_, ns_);
}

// Quadratures (integrals of flows): outside the Newton system, inside the error test.
void IdaStepper::init_quadratures() {
  if (nq_ == 0) return;
  void* mem = ida_->mem;
  const auto qs = sys_.quadrature_scales();
  for (int i = 0; i < nq_; ++i) qatol_.data()[i] = opt_.atol * qs[i];
  check(IDAQuadInit(mem, ida_quad, q_.v), "IDAQuadInit");
  check(IDAQuadSVtolerances(mem, opt_.rtol, qatol_.v), "IDAQuadSVtolerances");
  check(IDASetQuadErrCon(mem, SUNTRUE), "IDASetQuadErrCon");
}

void IdaStepper::init_sensitivities() {
  if (ns_ == 0) return;
  void* mem = ida_->mem;
  const booleantype err_con = opt_.sens_error_control ? SUNTRUE : SUNFALSE;
  yS_ = N_VCloneVectorArray(ns_, y_.v);
  ypS_ = N_VCloneVectorArray(ns_, y_.v);
  std::vector<std::vector<double>> yS0;
  sys_.initial_sensitivities(sens_ids_, yS0);
  for (int k = 0; k < ns_; ++k) {
    std::copy(yS0[k].begin(), yS0[k].end(), N_VGetArrayPointer(yS_[k]));
    N_VConst(0.0, ypS_[k]);
  }
  check(IDASensInit(mem, ns_, IDA_STAGGERED, ida_sens_res, yS_, ypS_), "IDASensInit");
  check(IDASensEEtolerances(mem), "IDASensEEtolerances");
  check(IDASetSensErrCon(mem, err_con), "IDASetSensErrCon");
  if (nq_ == 0) return;
  qS_ = N_VCloneVectorArray(ns_, q_.v);
  for (int k = 0; k < ns_; ++k) N_VConst(0.0, qS_[k]);
  check(IDAQuadSensInit(mem, ida_quad_sens, qS_), "IDAQuadSensInit");
  check(IDAQuadSensEEtolerances(mem), "IDAQuadSensEEtolerances");
  check(IDASetQuadSensErrCon(mem, err_con), "IDASetQuadSensErrCon");
}

// Consistent initial sensitivities come from one linear solve (consistent_sensitivities.hpp), not from
// IDACalcIC's sensitivity Newton: sensitivities are off during IDACalcIC and re-initialized after it.
void IdaStepper::sensitivity_initial_conditions(double t) {
  void* mem = ida_->mem;
  const booleantype err_con = opt_.sens_error_control ? SUNTRUE : SUNFALSE;
  std::vector<double*> s(ns_), sp(ns_);
  for (int k = 0; k < ns_; ++k) s[k] = N_VGetArrayPointer(yS_[k]), sp[k] = N_VGetArrayPointer(ypS_[k]);
  detail::consistent_sensitivities(sys_, user_.dense, t, y_.data(), yp_.data(), sens_ids_, s.data(), sp.data());
  check(IDAReInit(mem, t, y_.v, yp_.v), "IDAReInit");
  if (nq_ > 0) check(IDAQuadReInit(mem, q_.v), "IDAQuadReInit");
  check(IDASensReInit(mem, IDA_STAGGERED, yS_, ypS_), "IDASensReInit");
  check(IDASensEEtolerances(mem), "IDASensEEtolerances");
  // IDACalcIC's setup ran with sensitivities off and cleared their error-control flag: set it again.
  check(IDASetSensErrCon(mem, err_con), "IDASetSensErrCon");
  if (nq_ > 0) {
    check(IDAQuadSensReInit(mem, qS_), "IDAQuadSensReInit");
    check(IDAQuadSensEEtolerances(mem), "IDAQuadSensEEtolerances");
    check(IDASetQuadSensErrCon(mem, err_con), "IDASetQuadSensErrCon");
  }
}

// A dense run whose units keep the residual contract starts with an exact Newton on its algebraic states
// (consistent_start.hpp), IDACalcIC otherwise or when that Newton gives up.
int IdaStepper::start_consistently(size_t seg, double t0, double t1, SolverStats& stats) {
  void* mem = ida_->mem;
  int block = 0;
  if (dense_ && !user_.iterative) {
    for (int i = 0; i < n_; ++i) ewt_[i] = 1.0 / (opt_.rtol * std::abs(y_.data()[i]) + atol_.data()[i]);
    block = detail::consistent_start(sys_, user_.cache, t0, ewt_.data(), y_.data(), yp_.data(),
                                     seg == 0 && !j0_.empty() ? j0_.data() : nullptr);
    if (block > 0) {
      ++stats.newton_starts;
      check(IDAReInit(mem, t0, y_.v, yp_.v), "IDAReInit");
      if (nq_ > 0) check(IDAQuadReInit(mem, q_.v), "IDAQuadReInit");
      ida_->tune_refactoring(block);
      return 0;
    }
  }
  // IDACalcIC's Newton matrix is dF/dy + dF/dy' / h_ic with h_ic = 1e-3 (tout1 - t0); the exact one for its
  // unknowns (y' differential, y algebraic) lacks dF/dy of the differential states, so a long h_ic slows
  // Newton (headline scene, tout1 at the segment end: 55 residuals), while a very short one loosens the test
  // on y', whose correction is measured times h_ic. 1 % of the segment (15 residuals there); not the first
  // output time, so that results do not depend on which output times are asked for. That horizon grows with the
  // segment (with t_end when no breakpoint cuts it): where its Newton fails, the start is tried again from the same
  // values with a horizon ten times shorter (a loop with a swapped sieve deck: 1 % of 59 h fails, 1 % of 30 h not).
  constexpr int kShorterHorizons = 6;
  int flag = 0;
  for (int k = 0; k <= kShorterHorizons; ++k) {
    if (k > 0) {
      check(IDAReInit(mem, t0, y_.v, yp_.v), "IDAReInit");
      if (nq_ > 0) check(IDAQuadReInit(mem, q_.v), "IDAQuadReInit");
      user_.cache.valid = false;
    }
    const double tout1 = t0 + 0.01 * (t1 - t0) * std::pow(0.1, k);
    ++stats.calcic_starts;
    user_.fresh_only = true;
    if (user_.local) class_local_whole(user_.local, true);  // Newton from a guess: the exact matrix
    flag = IDACalcIC(mem, IDA_YA_YDP_INIT, tout1);
    if (user_.local) class_local_whole(user_.local, false);
    user_.fresh_only = false;
    if (flag >= 0) break;
  }
  if (flag < 0) {
    failed_call_ = "consistent initialization (IDACalcIC)";
    return flag;
  }
  check(IDAGetConsistentIC(mem, y_.v, yp_.v), "IDAGetConsistentIC");
  ida_->tune_refactoring();   // from the blocks IDACalcIC factored
  user_.cache.valid = false;  // evaluated at IDACalcIC's iterates
  return 0;
}

int IdaStepper::begin_segment(size_t seg, double t0, double t1, SolverStats& stats) {
  void* mem = ida_->mem;
  if (seg > 0) {
    add_current_counts(counts_);
    check(IDAReInit(mem, t0, y_.v, yp_.v), "IDAReInit");
    if (nq_ > 0 && !restored_) {
      realtype tq = t0;
      IDAGetQuad(mem, &tq, q_.v);
      check(IDAQuadReInit(mem, q_.v), "IDAQuadReInit");
    }
  }
  if (ns_ > 0) check(IDASensToggleOff(mem), "IDASensToggleOff");
  user_.cache.valid = false;  // a segment starts from a fresh Jacobian
  if (user_.structured) banded_lowrank_new_segment(user_.structured);
  const int flag = start_consistently(seg, t0, t1, stats);
  if (flag < 0) return flag;
  restored_ = false;
  if (jump_pending_) apply_jump(t0);
  if (ns_ > 0) sensitivity_initial_conditions(t0);
  check(IDASetStopTime(mem, t1), "IDASetStopTime");
  return 0;
}

int IdaStepper::advance(double tout, double& t) {
  realtype tret = t;
  const int flag = IDASolve(ida_->mem, tout, &tret, y_.v, yp_.v, IDA_NORMAL);
  if (flag < 0) failed_call_ = "IDASolve";
  t = tret;
  return flag;
}

Sample IdaStepper::sample(double t) {
  void* mem = ida_->mem;
  realtype tret = t;
  if (nq_ > 0 && t > 0) IDAGetQuad(mem, &tret, q_.v);
  if (ns_ > 0) {
    if (t > 0) IDAGetSens(mem, &tret, yS_);
    if (t > 0 && nq_ > 0) IDAGetQuadSens(mem, &tret, qS_);
    for (int k = 0; k < ns_; ++k) {
      yS_now_[k] = N_VGetArrayPointer(yS_[k]);
      if (nq_ > 0) qS_now_[k] = N_VGetArrayPointer(qS_[k]);
    }
  }
  Sample s;
  s.y = y_.data(), s.yp = yp_.data();
  if (nq_ > 0) s.q = q_.data();
  if (ns_ > 0) s.yS = yS_now_.data();
  if (ns_ > 0 && nq_ > 0 && t > 0) s.qS = qS_now_.data();
  return s;
}

// The next segment restarts from the sensitivities and quadratures at the end of this one.
void IdaStepper::end_segment(double, double t1) {
  void* mem = ida_->mem;
  realtype tret;
  if (ns_ > 0) {
    IDAGetSens(mem, &tret, yS_);
    IDAGetSensDky(mem, t1, 1, ypS_);
    if (nq_ > 0) IDAGetQuadSens(mem, &tret, qS_);
  }
  if (nq_ > 0) IDAGetQuad(mem, &tret, q_.v);
}

StepFailure IdaStepper::failure(int flag) {
  void* mem = ida_->mem;
  StepFailure f;
  realtype tcur = 0;
  IDAGetCurrentTime(mem, &tcur);
  f.t = tcur, f.y = y_.data(), f.yp = yp_.data();
  NVec w(n_, C_.ctx);
  IDAGetErrWeights(mem, w.v);
  f.weights.assign(w.data(), w.data() + n_);
  f.what = failed_call_;
  f.flag_text = ida_flag_text(flag) + (user_.last_error.empty() ? "" : " (" + user_.last_error + ")");
  return f;
}

void IdaStepper::add_current_counts(SolverStats& s) const {
  void* mem = ida_->mem;
  long v = 0;
  IDAGetNumSteps(mem, &v), s.steps += v;
  IDAGetNumLinSolvSetups(mem, &v), s.linear_setups += v;
  IDAGetNumNonlinSolvIters(mem, &v), s.nonlinear_iterations += v;
  IDAGetNumErrTestFails(mem, &v), s.error_test_failures += v;
  IDAGetNumNonlinSolvConvFails(mem, &v), s.nonlinear_failures += v;
  if (user_.iterative) {
    IDAGetNumLinIters(mem, &v), s.linear_iterations += v;
    IDAGetNumPrecEvals(mem, &v), s.preconditioner_setups += v;
    IDAGetNumLinConvFails(mem, &v), s.linear_failures += v;
  }
}

void IdaStepper::set_roots(int n, RootFunction g, const std::vector<int>& directions) {
  if (n == 0) return;
  n_roots_ = n;
  user_.roots = std::move(g);
  check(IDARootInit(ida_->mem, n, ida_roots), "IDARootInit");
  std::vector<int> dir = directions;
  check(IDASetRootDirection(ida_->mem, dir.data()), "IDASetRootDirection");
  // A disarmed event's g is a constant: IDAS need not warn that it is one.
  check(IDASetNoInactiveRootWarn(ida_->mem), "IDASetNoInactiveRootWarn");
}

std::vector<int> IdaStepper::roots() {
  std::vector<int> found(n_roots_, 0);
  if (n_roots_ > 0) check(IDAGetRootInfo(ida_->mem, found.data()), "IDAGetRootInfo");
  return found;
}

// The jump conditions at a state event (stepper.hpp, SensitivityJump), once the consistent y'+ after the event is
// known: the differential states' sensitivities and the quadratures' ones; the algebraic states' follow from the
// consistent sensitivities computed next.
void IdaStepper::apply_jump(double t) {
  jump_pending_ = false;
  if (ns_ == 0) return;
  const std::vector<double> id = sys_.differential_id();
  std::vector<double> qdot(std::max(nq_, 1), 0.0);
  if (nq_ > 0 && sys_.quadrature(t, y_.data(), yp_.data(), qdot.data()) != Status::kOk)
    throw SolverError("the quadrature rates after an event at t = " + fmt_num(t) + " s cannot be evaluated", t, "?", 0);
  for (int k = 0; k < ns_; ++k) {
    double* s = N_VGetArrayPointer(yS_[k]);
    for (int i = 0; i < n_; ++i)
      if (id[i] != 0.0) s[i] += (jump_.yp_before[i] - yp_.data()[i]) * jump_.tau[k];
    if (nq_ == 0) continue;
    double* sq = N_VGetArrayPointer(qS_[k]);
    for (int i = 0; i < nq_; ++i) sq[i] += (jump_.qdot_before[i] - qdot[i]) * jump_.tau[k];
  }
}

bool IdaStepper::save(StepperState& s) {
  s.y.assign(y_.data(), y_.data() + n_);
  s.yp.assign(yp_.data(), yp_.data() + n_);
  s.q.assign(q_.data(), q_.data() + nq_);
  s.yS.assign(ns_, {}), s.ypS.assign(ns_, {}), s.qS.assign(ns_, {});
  for (int k = 0; k < ns_; ++k) {
    const double* a = N_VGetArrayPointer(yS_[k]);
    const double* b = N_VGetArrayPointer(ypS_[k]);
    s.yS[k].assign(a, a + n_), s.ypS[k].assign(b, b + n_);
    if (nq_ > 0) s.qS[k].assign(N_VGetArrayPointer(qS_[k]), N_VGetArrayPointer(qS_[k]) + nq_);
  }
  return true;
}

void IdaStepper::restore(const StepperState& s) {
  std::copy(s.y.begin(), s.y.end(), y_.data());
  std::copy(s.yp.begin(), s.yp.end(), yp_.data());
  std::copy(s.q.begin(), s.q.end(), q_.data());
  for (int k = 0; k < ns_; ++k) {
    std::copy(s.yS[k].begin(), s.yS[k].end(), N_VGetArrayPointer(yS_[k]));
    std::copy(s.ypS[k].begin(), s.ypS[k].end(), N_VGetArrayPointer(ypS_[k]));
    if (nq_ > 0) std::copy(s.qS[k].begin(), s.qS[k].end(), N_VGetArrayPointer(qS_[k]));
  }
  restored_ = true;
}

void IdaStepper::finish(SolverStats& stats) {
  add_current_counts(counts_);
  add_counts(stats, counts_);
  stats.linear_solver = linear_solver_name(kind_);
  if (user_.structured) {  // a setup whose matrix was not band + low rank was factored densely: say how many
    const BandedLowRankStats b = banded_lowrank_stats(user_.structured);
    if (b.dense_setups > 0)
      stats.linear_solver += "; " + std::to_string(b.dense_setups) + " of " + std::to_string(b.setups) +
                             " setups dense LU (the matrix was not band + low rank" +
                             (b.untested_setups > 0 ? "; " + std::to_string(b.untested_setups) +
                                                          " without looking, after it was not twice in a row)"
                                                    : std::string(")"));
  }
  if (user_.local) {  // setups that factored the whole matrix (consistent initial values): say how many
    const ClassLocalStats c = class_local_stats(user_.local);
    if (c.classes == 0 && c.setups > 0)  // asked for where nothing is per class: not silently another solver
      stats.linear_solver += "; no state is per size class: every setup whole (dense LU)";
    else if (c.whole_setups > 0)
      stats.linear_solver += "; " + std::to_string(c.whole_setups) + " of " + std::to_string(c.setups) +
                             " setups whole (dense LU, consistent initial values)";
  }
  stats.method = "bdf (IDAS)";
  stats.method_reason = reason_;
}

}  // namespace granuflow::detail
