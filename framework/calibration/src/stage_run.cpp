#include "stage_run.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration_internal.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"

namespace granuflow {
namespace calib {

StageRun::StageRun(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                   const Stage& stage, const CalibrationOptions& opt, const std::map<std::string, double>& fixed)
    : space(make_space(*scene.flowsheet, stage)), observables(stage.observables), name(stage.name) {
  for (const auto& o : stage.observables) observable_unit(*scene.flowsheet, o);  // names checked once
  std::vector<std::unique_ptr<ExperimentModel>> all(exps.size());
  parallel_for(static_cast<int>(exps.size()), opt.num_threads, [&](int i) {
    all[i] = std::make_unique<ExperimentModel>(scene, reg, exps[i], stage.observables, space, fixed, opt);
  });
  for (auto& m : all)
    if (m->rows() > 0) models.push_back(std::move(m));
  if (models.empty()) {
    std::string names;
    for (const auto& o : stage.observables) names += (names.empty() ? "" : ", ") + o;
    throw ConfigError("stage '" + stage.name + "': no experiment has data for its observables (" +
                      (names.empty() ? std::string("all") : names) + "); give data for at least one of them");
  }
  for (auto& m : models) costs.push_back(std::make_unique<ExperimentCost>(m.get(), space.size(), opt.sigma_basis));
}

void StageRun::evaluate(const std::vector<double>& theta, std::vector<double>& r, std::vector<double>* J, int threads) {
  std::vector<std::vector<double>> rr(costs.size()), jj(costs.size());
  parallel_for(static_cast<int>(costs.size()), threads, [&](int i) {
    rr[i].resize(models[i]->rows());
    if (J) {
      costs[i]->at(theta.data(), rr[i], jj[i]);
    } else {
      costs[i]->compute(theta.data(), rr[i].data(), nullptr);
    }
  });
  r.clear();
  if (J) J->clear();
  for (size_t i = 0; i < costs.size(); ++i) {
    r.insert(r.end(), rr[i].begin(), rr[i].end());
    if (J) J->insert(J->end(), jj[i].begin(), jj[i].end());
  }
}

void StageRun::prepare(const double* theta, bool jacobian, int threads) {
  std::vector<int> order(costs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return costs[a]->last_seconds(jacobian) > costs[b]->last_seconds(jacobian); });
  parallel_for(static_cast<int>(order.size()), threads, [&](int i) { costs[order[i]]->prepare(theta, jacobian); });
}

ceres::Solver::Summary StageRun::solve(std::vector<double>& theta, const CalibrationOptions& opt, int max_iterations) {
  // Ceres writes each evaluation point into θ before it calls back, and the experiments are then solved here.
  struct Ahead : ceres::EvaluationCallback {
    StageRun& run;
    const double* theta;
    int threads;
    Ahead(StageRun& r, const double* t, int n) : run(r), theta(t), threads(n) {}
    void PrepareForEvaluation(bool jacobians, bool) override { run.prepare(theta, jacobians, threads); }
  } ahead(*this, theta.data(), opt.num_threads);
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.evaluation_callback = &ahead;
  ceres::Problem problem(po);
  const int n = space.size();
  problem.AddParameterBlock(theta.data(), n);
  for (auto& c : costs) problem.AddResidualBlock(c.get(), nullptr, theta.data());
  for (int k = 0; k < n; ++k) {
    problem.SetParameterLowerBound(theta.data(), k, space.theta_lower(k));
    problem.SetParameterUpperBound(theta.data(), k, space.theta_upper(k));
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.initial_trust_region_radius = opt.initial_trust_region_radius;
  so.function_tolerance = opt.function_tolerance;
  so.gradient_tolerance = opt.gradient_tolerance;
  so.parameter_tolerance = opt.parameter_tolerance;
  // Ceres itself on one thread: with more it sums the experiments' costs and gradients in per-thread parts, whose
  // grouping follows the thread count, and an accept/reject or stopping decision can then go the other way; the
  // experiments are solved in parallel before it evaluates (Ahead), which is where the time goes.
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  // No line search on bounded problems: each of its trials costs a Jacobian (a sensitivity solve per
  // experiment); a step that leaves the bounds is projected and judged by the trust region like any other.
  so.max_num_line_search_step_size_iterations = 0;
  // Converged once an accepted step lowers ½χ² by less than cost_change_tolerance: the optimum is then
  // closer than about sqrt(4 cost_change_tolerance) standard errors in every direction.
  struct SmallChange : ceres::IterationCallback {
    double tol;
    explicit SmallChange(double t) : tol(t) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      return s.iteration > 0 && s.step_is_successful && s.cost_change < tol ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                                            : ceres::SOLVER_CONTINUE;
    }
  } small_change(opt.cost_change_tolerance);
  if (opt.cost_change_tolerance > 0) so.callbacks.push_back(&small_change);
  // An interrupt (Ctrl-C) ends the stage after the iteration it arrives in; the experiments' runs stop at once and
  // report failed evaluations, which Ceres only sees as rejected steps: hence the check after Solve.
  struct StopOnInterrupt : ceres::IterationCallback {
    ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
      return interrupt_requested() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
    }
  } stop_on_interrupt;
  so.callbacks.push_back(&stop_on_interrupt);
  struct Report : ceres::IterationCallback {
    const StageRun& run;
    const CalibrationOptions& opt;
    Report(const StageRun& r, const CalibrationOptions& o) : run(r), opt(o) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      opt.progress({run.name, s.iteration, s.cost, run.simulations(), run.sensitivity_solves()});
      return ceres::SOLVER_CONTINUE;
    }
  } report(*this, opt);
  if (opt.progress) so.callbacks.insert(so.callbacks.begin(), &report);  // first: it sees the iteration that ends
  std::string why;
  if (!so.IsValid(&why)) throw ConfigError("Ceres options: " + why);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (interrupt_flagged())
    throw Interrupted("calibration interrupted in Ceres iteration " + std::to_string(summary.iterations.size()));
  return summary;
}

double StageRun::reweight(const std::vector<double>& theta) {
  double change = 0.0;
  for (auto& c : costs) change = std::max(change, c->reweight(theta.data()));
  return change;
}

std::vector<std::vector<double>> StageRun::sigmas() const {
  std::vector<std::vector<double>> v;
  for (const auto& c : costs) v.push_back(c->sigma());
  return v;
}

void StageRun::set_sigmas(const std::vector<std::vector<double>>& v) {
  for (size_t i = 0; i < costs.size() && i < v.size(); ++i) costs[i]->set_sigma(v[i]);
}

std::string StageRun::first_error() const {
  for (const auto& c : costs)
    if (!c->last_error().empty()) return c->last_error();
  return "";
}

void clamp_theta(const Space& s, std::vector<double>& th) {
  for (int k = 0; k < s.size(); ++k) th[k] = std::min(std::max(th[k], s.theta_lower(k)), s.theta_upper(k));
}

std::vector<double> start_theta(const Space& s, const std::map<std::string, double>& p) {
  std::vector<double> th(s.size());
  for (int k = 0; k < s.size(); ++k) {
    const double v = std::min(std::max(p.at(s.names[k]), s.lower[k]), s.upper[k]);
    th[k] = s.to_theta(k, v);
  }
  return th;
}

namespace {

// Covariance (JᵀJ)⁻¹ in θ by a scaled pseudo-inverse; directions the data do not see get infinite variance.
void covariance(const std::vector<double>& Jv, long rows, int n, std::vector<double>& cov) {
  Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(Jv.data(), rows, n);
  const Eigen::MatrixXd A = J.transpose() * J;
  Eigen::VectorXd d(n);
  for (int k = 0; k < n; ++k) d[k] = A(k, k) > 0 ? 1.0 / std::sqrt(A(k, k)) : 0.0;
  const Eigen::MatrixXd S = d.asDiagonal() * A * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  const Eigen::VectorXd ev = es.eigenvalues();
  const double tol = 1e-12 * std::max(ev.maxCoeff(), 1e-300);
  Eigen::MatrixXd Sinv = Eigen::MatrixXd::Zero(n, n);
  std::vector<bool> unseen(n, false);
  for (int j = 0; j < n; ++j) {
    const Eigen::VectorXd v = es.eigenvectors().col(j);
    if (ev[j] > tol) {
      Sinv += v * v.transpose() / ev[j];
    } else {
      for (int k = 0; k < n; ++k)
        if (std::abs(v[k]) > 1e-3) unseen[k] = true;
    }
  }
  cov.assign(size_t(n) * n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) cov[size_t(i) * n + k] = d[i] * Sinv(i, k) * d[k];
  for (int k = 0; k < n; ++k)
    if (unseen[k] || d[k] == 0.0) cov[size_t(k) * n + k] = std::numeric_limits<double>::infinity();
}

// Gradient Jᵀr and curvature (JᵀJ)_kk at the estimate; flat: χ² would change by less than flat_delta_chi2 with
// θ_k anywhere within its bounds (to second order), so nothing the stage watches responds to it here.
void local_diagnostics(const Space& sp, const std::vector<double>& theta, const std::vector<double>& theta_start,
                       const std::vector<double>& r, const std::vector<double>& J, const CalibrationOptions& opt,
                       StageResult& res) {
  const int n = sp.size();
  res.gradient.assign(n, 0.0);
  res.curvature.assign(n, 0.0);
  for (long i = 0; i < res.residuals; ++i)
    for (int k = 0; k < n; ++k) {
      const double jk = J[size_t(i) * n + k];
      res.gradient[k] += jk * r[i];
      res.curvature[k] += jk * jk;
    }
  res.moved = false;
  for (int k = 0; k < n; ++k) {
    const double span = sp.theta_upper(k) - sp.theta_lower(k);
    if (res.curvature[k] * span * span < opt.flat_delta_chi2) res.flat.push_back(sp.names[k]);
    if (std::abs(theta[k] - theta_start[k]) > 1e-9 * (1 + std::abs(theta_start[k]))) res.moved = true;
  }
}

void fill_estimates(const Space& sp, const std::vector<double>& theta, const std::vector<double>& theta_start,
                    StageResult& res) {
  const int n = sp.size();
  res.estimates.resize(n);
  for (int k = 0; k < n; ++k) {
    Estimate& e = res.estimates[k];
    e.name = sp.names[k];
    e.transform = sp.transform[k];
    e.logarithmic = sp.logarithmic[k];
    e.start = sp.to_p(k, theta_start[k]);
    e.theta = theta[k];
    e.value = sp.to_p(k, theta[k]);
    e.lower = sp.lower[k];
    e.upper = sp.upper[k];
    const double span = sp.theta_upper(k) - sp.theta_lower(k);
    e.at_bound = theta[k] <= sp.theta_lower(k) + 1e-6 * span || theta[k] >= sp.theta_upper(k) - 1e-6 * span;
  }
}

// Covariance and correlations of the estimates, their standard errors, and why one is flagged.
void add_statistics(const Space& sp, const std::vector<double>& J, const CalibrationOptions& opt, StageResult& res) {
  const int n = sp.size();
  covariance(J, res.residuals, n, res.covariance);
  if (opt.scale_covariance && std::isfinite(res.chi2_reduced))
    for (double& c : res.covariance) c *= res.chi2_reduced;
  res.correlation.assign(size_t(n) * n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      const double ci = res.covariance[size_t(i) * n + i], ck = res.covariance[size_t(k) * n + k];
      res.correlation[size_t(i) * n + k] = i == k ? 1.0
                                           : (std::isfinite(ci) && std::isfinite(ck) && ci > 0 && ck > 0)
                                               ? res.covariance[size_t(i) * n + k] / std::sqrt(ci * ck)
                                               : std::numeric_limits<double>::quiet_NaN();
    }
  for (int k = 0; k < n; ++k) {
    Estimate& e = res.estimates[k];
    e.se_theta = std::sqrt(res.covariance[size_t(k) * n + k]);
    e.se = e.se_theta * sp.dp_dtheta(k, e.theta);
    e.rel_se =
        (e.transform == Transform::kLog || e.logarithmic) ? e.se_theta : e.se / std::max(std::abs(e.value), 1e-300);
    std::vector<std::string> why;
    if (!std::isfinite(e.se))
      why.push_back("the data do not constrain it (singular covariance)");
    else if (e.rel_se > opt.rse_threshold)
      why.push_back("relative standard error " + fmt(e.rel_se, 3) + " > " + fmt(opt.rse_threshold, 3));
    for (int i = 0; i < n; ++i) {
      const double c = res.correlation[size_t(k) * n + i];
      if (i != k && std::isfinite(c) && std::abs(c) > opt.correlation_threshold)
        why.push_back("correlated with " + sp.names[i] + " (r = " + fmt(c, 3) + ")");
    }
    if (e.at_bound) why.push_back("at a bound");
    for (size_t j = 0; j < why.size(); ++j) e.flag += (j ? "; " : "") + why[j];
    e.identifiable = std::isfinite(e.se) && e.rel_se <= opt.rse_threshold;
  }
}

}  // namespace

StageResult run_stage(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                      const Stage& stage, const CalibrationOptions& opt, std::map<std::string, double>& params,
                      bool statistics, int max_iterations, const std::vector<std::vector<double>>* sigmas,
                      std::vector<std::vector<double>>* sigmas_out) {
  const auto t0 = Clock::now();
  StageRun run(scene, reg, exps, stage, opt, params);
  const Space& sp = run.space;
  const int n = sp.size();
  std::vector<double> theta = start_theta(sp, params);
  const std::vector<double> theta_start = theta;
  StageResult res;
  res.name = stage.name;
  res.observables = stage.observables;
  res.jacobian_method = to_string(opt.jacobian);
  if (sigmas) run.set_sigmas(*sigmas);
  std::vector<double> r, J;
  // Least squares with σ fixed, then σ_rel |m| re-taken at the optimum, until the weights settle.
  const int passes = sigmas ? 1 : opt.max_reweighting_passes;
  for (int pass = 0; pass < passes; ++pass) {
    const ceres::Solver::Summary summary = run.solve(theta, opt, max_iterations);
    if (pass == 0) res.initial_cost = summary.initial_cost;
    res.termination = ceres::TerminationTypeToString(summary.termination_type);
    res.message = summary.message;
    res.usable = summary.IsSolutionUsable();
    res.iterations += static_cast<int>(summary.iterations.size()) - 1;
    for (const auto& it : summary.iterations) res.iteration_costs.push_back(it.cost);
    ++res.passes;
    if (!res.usable) {
      const std::string err = run.first_error();
      throw CalibrationError("stage '" + stage.name + "' failed: " + summary.message +
                             (err.empty() ? "" : " (" + err + ")"));
    }
    clamp_theta(sp, theta);
    run.evaluate(theta, r, &J, opt.num_threads);  // Ceres' last Jacobian, unless a bound moved θ
    res.weight_change = run.reweight(theta);
    if (res.weight_change <= opt.reweighting_tolerance) break;
  }
  run.evaluate(theta, r, &J, opt.num_threads);  // at the final weights (no simulation: cached and rescaled)
  res.cost = half_sum_squares(r);
  res.residuals = static_cast<long>(r.size());
  const long dof = res.residuals - n;
  res.chi2_reduced = dof > 0 ? 2 * res.cost / dof : std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < n; ++k) params[sp.names[k]] = sp.to_p(k, theta[k]);
  local_diagnostics(sp, theta, theta_start, r, J, opt, res);
  res.sensitivity_retries = run.sensitivity_retries();
  fill_estimates(sp, theta, theta_start, res);
  if (statistics) add_statistics(sp, J, opt, res);
  res.simulations = run.simulations();
  res.sensitivity_solves = run.sensitivity_solves();
  res.wall_time_s = seconds_since(t0);
  if (sigmas_out) *sigmas_out = run.sigmas();
  return res;
}

}  // namespace calib

using calib::StageRun;

// ---------------------------------------------------------------- StageProblem

struct StageProblem::Impl {
  CalibrationOptions opt;
  std::map<std::string, double> start;
  std::unique_ptr<StageRun> run;
};

StageProblem::StageProblem(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                           const Stage& stage, const CalibrationOptions& opt,
                           const std::map<std::string, double>& start)
    : impl_(new Impl) {
  try {
    opt.validate();
    calib::validate_experiments(exps);
    impl_->opt = opt;
    impl_->start = start;
    for (const auto& f : stage.free)
      if (!impl_->start.count(f.name)) impl_->start[f.name] = scene.flowsheet->param(f.name);
    impl_->run = std::make_unique<StageRun>(scene, reg, exps, stage, impl_->opt, impl_->start);
  } catch (...) {
    delete impl_;
    throw;
  }
}
StageProblem::~StageProblem() { delete impl_; }
int StageProblem::num_parameters() const { return impl_->run->space.size(); }
int StageProblem::num_residuals() const { return static_cast<int>(impl_->run->rows()); }
std::vector<double> StageProblem::theta0() const { return calib::start_theta(impl_->run->space, impl_->start); }
std::vector<double> StageProblem::to_theta(const std::vector<double>& p) const {
  std::vector<double> th(p.size());
  for (size_t k = 0; k < p.size(); ++k) th[k] = impl_->run->space.to_theta(static_cast<int>(k), p[k]);
  return th;
}
std::vector<double> StageProblem::to_params(const std::vector<double>& th) const {
  std::vector<double> p(th.size());
  for (size_t k = 0; k < th.size(); ++k) p[k] = impl_->run->space.to_p(static_cast<int>(k), th[k]);
  return p;
}
void StageProblem::evaluate(const std::vector<double>& theta, std::vector<double>& r, std::vector<double>* J) {
  if (static_cast<int>(theta.size()) != num_parameters())
    throw ConfigError("StageProblem::evaluate: theta has " + std::to_string(theta.size()) + " values, the stage " +
                      std::to_string(num_parameters()) + " free parameters");
  impl_->run->evaluate(theta, r, J, impl_->opt.num_threads);
}
long StageProblem::simulations() const { return impl_->run->simulations(); }
long StageProblem::sensitivity_solves() const { return impl_->run->sensitivity_solves(); }

}  // namespace granuflow
