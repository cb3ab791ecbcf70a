#include "ode_simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "granuflow/errors.hpp"
#include "ode_integrators.hpp"
#include "run_common.hpp"
#include "run_driver.hpp"
#include "solver_setup.hpp"

namespace granuflow::detail {

std::string first_algebraic_state(const Flowsheet& fs) {
  for (int i = 0; i < fs.n_states() - fs.n_explicit_states(); ++i)
    if (fs.state_spec(i).kind == StateKind::Algebraic)
      return "unit '" + fs.units()[fs.state_unit(i)].name + "', state '" + fs.state_spec(i).name + "'";
  return "";
}

namespace {

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

std::string describe(Method method, bool gmres = false) {
  if (method == Method::kBdf)
    return gmres ? "bdf (CVODES, Newton with GMRES)" : "bdf (CVODES, Newton with the exact Jacobian)";
  if (method == Method::kAdams) return "adams (CVODES, fixed-point iteration)";
  return "erk (ARKODE, Dormand-Prince 5(4))";
}

// CVODES or ARKODE as a stepper of the run driver. Breakpoints restart the integrator from the state, quadratures
// and sensitivities where the last segment ended. A non-stiff method that auto chose gets a step budget per output
// interval; past it the run goes on with BDF from where it stopped (stiffness the start did not show).
class OdeStepper : public Stepper {
 public:
  OdeStepper(DaeSystem& sys, const SimOptions& opt, OdeUser& user, const std::vector<int>& sens_ids, Method method,
             bool may_switch, long budget, std::string reason, LinearSolverKind kind)
      : opt_(opt),
        user_(user),
        method_(method),
        first_(method),
        may_switch_(may_switch),
        budget_(budget),
        reason_(std::move(reason)),
        kind_(kind),
        n_(sys.size()),
        nq_(sys.n_quadratures()),
        ns_(static_cast<int>(sens_ids.size())),
        y_(n_),
        atol_(n_),
        qatol_(std::max(nq_, 1), 1.0),
        q_(std::max(nq_, 1), 0.0),
        yp_(n_),
        yS_(ns_, std::vector<double>(n_)),
        qS_(ns_, std::vector<double>(std::max(nq_, 1), 0.0)),
        ys_(ns_),
        qs_(ns_) {
    std::vector<double> y0;
    sys.initial_values(y0);
    std::copy(y0.begin(), y0.begin() + n_, y_.begin());
    const auto sc = sys.scales();
    for (int i = 0; i < n_; ++i) atol_[i] = opt.atol * sc[i];
    const auto qsc = sys.quadrature_scales();
    for (int i = 0; i < nq_; ++i) qatol_[i] = opt.atol * qsc[i];
    cur_ = make(method_, 0.0, y_.data());
    if (ns_ == 0) return;
    std::vector<std::vector<double>> yS0;
    sys.initial_sensitivities(sens_ids, yS0);
    for (int k = 0; k < ns_; ++k) std::copy(yS0[k].begin(), yS0[k].begin() + n_, yS_[k].begin());
    cur_->restart(0.0, y_.data(), q_.data(), yS_, qS_);  // the initial state's own sensitivities (d N0 / d v0 ...)
  }

  int begin_segment(size_t seg, double t0, double t1, SolverStats&) override {
    if (seg > 0) cur_->restart(t0, y_.data(), q_.data(), yS_, qS_);
    cur_->set_stop(t1);
    t1_ = t1;
    return 0;
  }

  int advance(double tout, double& t) override {
    for (;;) {
      const int flag = cur_->advance(tout, y_.data(), &t);
      if (!(flag < 0 && may_switch_ && method_ != Method::kBdf && cur_->too_much_work(flag))) return flag;
      switch_to_bdf(t);
    }
  }

  bool segment_done(int, double t, double t1) const override { return t >= t1 * (1 - 1e-14); }

  Sample sample(double t) override {
    if (t > 0) {
      cur_->quadratures(t, q_.data());
      if (ns_ > 0) cur_->sensitivities(t, yS_, qS_);
    }
    user_.rhs(t, y_.data(), yp_.data());
    for (int k = 0; k < ns_; ++k) ys_[k] = yS_[k].data(), qs_[k] = qS_[k].data();
    Sample s;
    s.y = y_.data(), s.yp = yp_.data();
    if (nq_ > 0) s.q = q_.data();
    if (ns_ > 0) s.yS = ys_.data();
    if (ns_ > 0 && nq_ > 0) s.qS = qs_.data();
    return s;
  }

  void end_segment(double t0, double t1) override {
    if (t1 > t0) cur_->quadratures(t1, q_.data());
    if (ns_ > 0 && t1 > t0) cur_->sensitivities(t1, yS_, qS_);
  }

  StepFailure failure(int flag) override {
    StepFailure f;
    f.what = std::string("integration (") + to_string(method_) + ")";
    f.flag_text = cur_->flag_text(flag) + (user_.last_error.empty() ? "" : " (" + user_.last_error + ")");
    failed_yp_.resize(n_);
    f.weights.resize(n_);
    f.t = cur_->failed_state(failed_yp_.data(), f.weights.data());
    f.y = y_.data(), f.yp = failed_yp_.data();
    return f;
  }

  void finish(SolverStats& stats) override {
    cur_->add_stats(stats);
    add_counts(stats, retired_counts_);
    const bool gmres = kind_ == LinearSolverKind::kGmres;
    stats.method =
        retired_.empty() ? describe(method_, gmres) : describe(first_, gmres) + ", then " + describe(method_, gmres);
    stats.method_reason = reason_;
    stats.linear_solver = method_ != Method::kBdf                  ? "none"
                          : kind_ == LinearSolverKind::kBanded     ? "dense (Eigen LU): banded is IDAS's only"
                          : kind_ == LinearSolverKind::kClassLocal ? "dense (Eigen LU): class_local is IDAS's only"
                                                                   : linear_solver_name(kind_);
  }

 private:
  std::unique_ptr<OdeIntegrator> make(Method m, double t0, const double* y0) {
    const long steps = (may_switch_ && m != Method::kBdf) ? std::min(budget_, opt_.max_steps) : opt_.max_steps;
    if (m == Method::kErk) return make_erk(C_.ctx, user_, opt_, t0, y0, atol_, qatol_, steps);
    return make_cvode(C_.ctx, user_, m == Method::kBdf, opt_, t0, y0, atol_, qatol_, steps);
  }

  // Stiffness the start did not show: BDF from here on, from the state, quadratures and sensitivities reached.
  void switch_to_bdf(double t) {
    cur_->quadratures(t, q_.data());
    if (ns_ > 0) cur_->sensitivities(t, yS_, qS_);
    std::ostringstream os;
    os << "; " << to_string(method_) << " needed more than " << budget_ << " steps before t = " << fmt_num(t)
       << " s (stiff there): bdf from then on";
    reason_ += os.str();
    cur_->add_stats(retired_counts_);
    retired_.push_back(std::move(cur_));
    method_ = Method::kBdf;
    cur_ = make(Method::kBdf, t, y_.data());
    cur_->restart(t, y_.data(), q_.data(), yS_, qS_);
    cur_->set_stop(t1_);
  }

  const SimOptions& opt_;
  OdeUser& user_;
  Method method_, first_;
  bool may_switch_;
  long budget_;
  std::string reason_;
  LinearSolverKind kind_;
  int n_, nq_, ns_;
  std::vector<double> y_, atol_, qatol_, q_, yp_, failed_yp_;
  std::vector<std::vector<double>> yS_, qS_;
  std::vector<const double*> ys_, qs_;
  double t1_ = 0.0;
  Context C_;
  std::unique_ptr<OdeIntegrator> cur_;
  std::vector<std::unique_ptr<OdeIntegrator>> retired_;
  SolverStats retired_counts_;
};

}  // namespace

SimResult simulate_ode(Flowsheet& fs, const SimOptions& opt, Method requested,
                       std::chrono::steady_clock::time_point wall0) {
  // Explicit units are inlined (their states are no unknowns of an ODE); a Newton matrix over inlined units is the
  // dense Schur complement, so BDF on a system too large for dense algebra goes to IDAS instead.
  const LinearSolverKind kind = choose_linear_solver(fs, opt.linear_solver, opt.dense_limit, false);
  // banded, class_local: BDF factors its Newton matrix densely (those solvers are IDAS's)
  const bool dense = kind == LinearSolverKind::kDense || kind == LinearSolverKind::kBanded ||
                     kind == LinearSolverKind::kClassLocal,
             gmres = kind == LinearSolverKind::kGmres;
  if (requested == Method::kBdf && kind == LinearSolverKind::kSparse && fs.n_explicit_states() > 0)
    throw NotAnOde("BDF with sparse linear algebra needs the explicit units as unknowns");
  if (gmres && !opt.sensitivities.empty())
    throw ConfigError("sensitivities need a direct linear solver (solver.linear_solver: dense or sparse), not gmres");
  const std::shared_ptr<DaeSystem> held = fs.take_system(true);
  DaeSystem& sys = *held;
  const int n = sys.size(), nq = sys.n_quadratures();
  const std::vector<int> sens_ids = sensitivity_ids(fs, opt);
  const int ns = static_cast<int>(sens_ids.size());
  if (requested == Method::kErk && ns > 0)
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

  Method method = requested;
  std::string reason = "asked for (solver.method)";
  double predicted_steps = 0.0;
  if (requested == Method::kAuto) {
    const double rho = spectral_radius(user, 0.0, y, sys.scales());
    predicted_steps = rho * opt.t_end / kErkStability;
    std::ostringstream os;
    os << "an ODE; spectral radius of df/dy at the start " << fmt_num(rho) << " 1/s over " << fmt_num(opt.t_end)
       << " s: about " << fmt_num(std::ceil(predicted_steps)) << " explicit steps for stability alone";
    if (predicted_steps <= kErkStepBudget) {
      method = ns > 0 ? Method::kAdams : Method::kErk;
      os << " (non-stiff" << (ns > 0 ? "; sensitivities asked for, so Adams rather than Runge-Kutta)" : ")");
    } else {
      method = Method::kBdf;
      os << " (stiff)";
      if (kind == LinearSolverKind::kSparse && fs.n_explicit_states() > 0)
        throw NotAnOde(os.str() + ", too large for a dense Newton matrix");
    }
    reason = os.str();
  }
  // A non-stiff method that auto chose gets a step budget per output interval; past it the run goes on with BDF.
  const bool may_switch = requested == Method::kAuto && method != Method::kBdf;
  const long budget = may_switch ? static_cast<long>(std::max(10.0 * predicted_steps, 5000.0)) : opt.max_steps;
  OdeStepper stepper(sys, opt, user, sens_ids, method, may_switch, budget, reason, kind);
  return drive(fs, sys, opt, sens_ids, stepper, wall0);
}

}  // namespace granuflow::detail
