#include "granuflow/calibration.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <iomanip>
#include <limits>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "granuflow/errors.hpp"
#include "granuflow/output_sensitivity.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow {

// ---------------------------------------------------------------- enums and options

std::string to_string(Transform t) { return t == Transform::kLog ? "log" : "none"; }
Transform transform_from_string(const std::string& s) {
  if (s == "none") return Transform::kNone;
  if (s == "log") return Transform::kLog;
  throw ConfigError("transform '" + s + "': not one of none, log");
}
std::string to_string(SigmaBasis b) { return b == SigmaBasis::kData ? "data" : "model"; }
SigmaBasis sigma_basis_from_string(const std::string& s) {
  if (s == "model") return SigmaBasis::kModel;
  if (s == "data") return SigmaBasis::kData;
  throw ConfigError("sigma_basis '" + s + "': not one of model, data");
}
std::string to_string(JacobianMethod m) {
  return m == JacobianMethod::kCentralDifferences ? "central_differences" : "sensitivities";
}
JacobianMethod jacobian_method_from_string(const std::string& s) {
  if (s == "sensitivities") return JacobianMethod::kSensitivities;
  if (s == "central_differences") return JacobianMethod::kCentralDifferences;
  throw ConfigError("jacobian '" + s + "': not one of sensitivities, central_differences");
}

void CalibrationOptions::validate() const {
  auto fail = [](const std::string& field, double v, const std::string& rule) {
    throw ConfigError(violation("CalibrationOptions." + field, v, "", rule));
  };
  if (max_iterations < 1) fail("max_iterations", max_iterations, "max_iterations >= 1");
  if (!(function_tolerance > 0)) fail("function_tolerance", function_tolerance, "function_tolerance > 0");
  if (!(gradient_tolerance > 0)) fail("gradient_tolerance", gradient_tolerance, "gradient_tolerance > 0");
  if (!(parameter_tolerance > 0)) fail("parameter_tolerance", parameter_tolerance, "parameter_tolerance > 0");
  if (num_threads < 1) fail("num_threads", num_threads, "num_threads >= 1");
  if (!(fd_step > 0 && fd_step < 1)) fail("fd_step", fd_step, "0 < fd_step < 1");
  if (!(rtol > 0 && rtol < 1)) fail("rtol", rtol, "0 < rtol < 1");
  if (!(atol > 0)) fail("atol", atol, "atol > 0");
  if (!(rse_threshold > 0)) fail("rse_threshold", rse_threshold, "rse_threshold > 0");
  if (!(correlation_threshold > 0 && correlation_threshold <= 1))
    fail("correlation_threshold", correlation_threshold, "0 < correlation_threshold <= 1");
  if (!(profile_delta_chi2 > 0)) fail("profile_delta_chi2", profile_delta_chi2, "profile_delta_chi2 > 0");
  if (!(profile_max_offset > 0)) fail("profile_max_offset", profile_max_offset, "profile_max_offset > 0");
  if (profile_max_points < 1) fail("profile_max_points", profile_max_points, "profile_max_points >= 1");
  if (!(cost_change_tolerance >= 0)) fail("cost_change_tolerance", cost_change_tolerance, "cost_change_tolerance >= 0");
  if (!(initial_trust_region_radius > 0))
    fail("initial_trust_region_radius", initial_trust_region_radius, "initial_trust_region_radius > 0");
  if (max_reweighting_passes < 1) fail("max_reweighting_passes", max_reweighting_passes, "max_reweighting_passes >= 1");
  if (!(reweighting_tolerance >= 0)) fail("reweighting_tolerance", reweighting_tolerance, "reweighting_tolerance >= 0");
  if (!(flat_delta_chi2 > 0)) fail("flat_delta_chi2", flat_delta_chi2, "flat_delta_chi2 > 0");
  if (flat_scan_points < 0 || flat_scan_points == 1 || flat_scan_points == 2)
    fail("flat_scan_points", flat_scan_points, "flat_scan_points = 0 (off) or >= 3");
  if (!(restart_delta_chi2 > 0)) fail("restart_delta_chi2", restart_delta_chi2, "restart_delta_chi2 > 0");
  if (max_restarts < 0) fail("max_restarts", max_restarts, "max_restarts >= 0");
}

namespace calibration_testing {
std::function<bool(const std::string&)> fail_sensitivity_solve;
}

std::string observable_unit(const Flowsheet& fs, const std::string& name) {
  for (const auto& u : fs.units())
    for (const auto& o : u.spec.outputs())
      if (u.name + "." + o.name == name) return o.unit;
  const auto states = fs.state_names();
  for (size_t i = 0; i < states.size(); ++i)
    if (states[i] == name) return fs.state_spec(static_cast<int>(i)).unit;
  const auto outs = fs.output_names();
  std::string some;
  for (size_t i = 0; i < outs.size() && i < 12; ++i) some += (some.empty() ? "" : ", ") + outs[i];
  throw ConfigError("observable '" + name + "' is neither a reported output nor a state of flowsheet '" + fs.name() +
                    "' (outputs: " + some + ", ...; states: unit.state)");
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Runs f(0..n-1) on up to `threads` threads; the first exception (by index) is rethrown.
template <class F>
void parallel_for(int n, int threads, F&& f) {
  threads = std::max(1, std::min(threads, n));
  std::vector<std::exception_ptr> errors(n);
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i; (i = next++) < n;) {
      try {
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

// What Observation and Experiment promise (calibration.hpp): the loss indexes values by times and divides by σ.
void validate_experiments(const std::vector<Experiment>& exps) {
  for (const auto& e : exps) {
    if (!(e.t_end >= 0) || !std::isfinite(e.t_end))
      throw ConfigError(
          violation("experiment '" + e.name + "'.t_end", e.t_end, "s", "0 <= t_end < inf (0: the last sample time)"));
    for (const auto& o : e.observations) {
      const std::string w = "experiment '" + e.name + "': observation " + o.name;
      if (o.t.size() != o.value.size())
        throw ConfigError(w + ": " + std::to_string(o.t.size()) + " times but " + std::to_string(o.value.size()) +
                          " values");
      if ((o.sigma_abs > 0) == (o.sigma_rel > 0))
        throw ConfigError(w + ": give exactly one of sigma_abs > 0, sigma_rel > 0 (got " + std::to_string(o.sigma_abs) +
                          ", " + std::to_string(o.sigma_rel) + ")");
      if (!(o.sigma_abs >= 0 && o.sigma_rel >= 0) || !std::isfinite(o.sigma_abs) || !std::isfinite(o.sigma_rel))
        throw ConfigError(w + ": sigma must be finite and >= 0");
      for (size_t i = 0; i < o.t.size(); ++i) {
        if (!(o.t[i] >= 0) || !std::isfinite(o.t[i]) || (i > 0 && !(o.t[i] > o.t[i - 1])))
          throw ConfigError(violation(w + ".t[" + std::to_string(i) + "]", o.t[i], "s", "t >= 0, finite, increasing"));
        if (e.t_end > 0 && o.t[i] > e.t_end)
          throw ConfigError(violation(w + ".t[" + std::to_string(i) + "]", o.t[i], "s",
                                      "t <= t_end = " + std::to_string(e.t_end) + " s"));
        if (std::isinf(o.value[i]))
          throw ConfigError(violation(w + ".value[" + std::to_string(i) + "] at t = " + std::to_string(o.t[i]) + " s",
                                      o.value[i], "", "a finite number (NaN: not measured)"));
      }
    }
  }
}

// The free parameters of a stage and the map θ <-> p.
struct Space {
  std::vector<std::string> names;
  std::vector<Transform> transform;
  std::vector<bool> logarithmic;
  std::vector<double> lower, upper;  // SI

  int size() const { return static_cast<int>(names.size()); }
  double to_p(int k, double th) const { return transform[k] == Transform::kLog ? std::exp(th) : th; }
  double to_theta(int k, double p) const { return transform[k] == Transform::kLog ? std::log(p) : p; }
  double dp_dtheta(int k, double th) const { return transform[k] == Transform::kLog ? std::exp(th) : 1.0; }
  double theta_lower(int k) const { return to_theta(k, lower[k]); }
  double theta_upper(int k) const { return to_theta(k, upper[k]); }
};

Space make_space(const Flowsheet& fs, const Stage& stage) {
  Space s;
  std::set<std::string> seen;
  for (const auto& f : stage.free) {
    const std::string where = "stage '" + stage.name + "': free parameter " + f.name;
    const int id = fs.param_id(f.name);
    if (!seen.insert(f.name).second) throw ConfigError(where + " is listed twice");
    if (fs.has_input(id)) throw ConfigError(where + " is a time-dependent input; only constants can be calibrated");
    const ParamSpec& spec = fs.param_spec(id);
    const auto [allowed_lo, allowed_hi] = fs.bounds(id);  // declared, narrowed by linked followers
    const double lo = f.lower.value_or(allowed_lo), hi = f.upper.value_or(allowed_hi);
    if (std::isnan(lo)) throw ConfigError(violation(where + ".lower", lo, spec.unit, "lower is a number"));
    if (std::isnan(hi)) throw ConfigError(violation(where + ".upper", hi, spec.unit, "upper is a number"));
    if (lo < allowed_lo)
      throw ConfigError(
          violation(where + ".lower", lo, spec.unit, "lower >= allowed lower bound " + fmt_num(allowed_lo)));
    if (hi > allowed_hi)
      throw ConfigError(
          violation(where + ".upper", hi, spec.unit, "upper <= allowed upper bound " + fmt_num(allowed_hi)));
    if (!(hi > lo)) throw ConfigError(violation(where + ".upper", hi, spec.unit, "upper > lower"));
    if (f.transform == Transform::kLog && !(lo > 0))
      throw ConfigError(violation(where + ".lower", lo, spec.unit, "lower > 0 for transform log"));
    s.names.push_back(f.name);
    s.transform.push_back(f.transform);
    s.logarithmic.push_back(f.logarithmic.value_or(spec.name.rfind("ln_", 0) == 0));
    s.lower.push_back(lo);
    s.upper.push_back(hi);
  }
  if (s.names.empty()) throw ConfigError("stage '" + stage.name + "' has no free parameters");
  return s;
}

// One experiment on its own clone of the scene: the rows of the stage's loss and the model at them.
class ExperimentModel {
 public:
  ExperimentModel(const Scene& scene, const Registry<Unit>& reg, const Experiment& e,
                  const std::vector<std::string>& observables, const Space& space,
                  const std::map<std::string, double>& fixed, const CalibrationOptions& opt)
      : scene_(clone_scene(scene, reg)), space_(space), opt_(opt), name_(e.name) {
    Flowsheet& fs = *scene_.flowsheet;
    for (const auto& [k, v] : fixed) fs.set_param(k, v);
    for (const auto& [k, v] : e.settings) {
      for (const auto& n : space.names)
        if (n == k) throw ConfigError("experiment '" + e.name + "' sets " + k + ", a free parameter of the stage");
      fs.set_param(k, v);
    }
    const auto outs = fs.output_names();
    const auto states = fs.state_names();
    std::set<double> times;
    double t_last = 0.0;
    for (const auto& o : e.observations) {
      if (!observables.empty() && std::find(observables.begin(), observables.end(), o.name) == observables.end())
        continue;
      Obs ob;
      ob.src = &o;
      auto it = std::find(outs.begin(), outs.end(), o.name);
      if (it != outs.end()) {
        ob.state = false, ob.index = static_cast<int>(it - outs.begin());
        any_output_ = true;
      } else {
        auto is = std::find(states.begin(), states.end(), o.name);
        if (is == states.end()) observable_unit(fs, o.name);  // throws with the valid names
        ob.state = true, ob.index = static_cast<int>(is - states.begin());
      }
      for (size_t i = 0; i < o.t.size(); ++i) {
        if (!std::isfinite(o.value[i])) continue;
        times.insert(o.t[i]);
        t_last = std::max(t_last, o.t[i]);
        ob.samples.push_back(static_cast<int>(i));
        data_.push_back(o.value[i]);
        sigma_abs_.push_back(o.sigma_abs);
        sigma_rel_.push_back(o.sigma_abs > 0 ? 0.0 : o.sigma_rel);
      }
      obs_.push_back(std::move(ob));
    }
    t_out_.assign(times.begin(), times.end());
    for (auto& ob : obs_)
      for (int i : ob.samples)
        ob.time_index.push_back(
            static_cast<int>(std::lower_bound(t_out_.begin(), t_out_.end(), ob.src->t[i]) - t_out_.begin()));
    sim_ = scene_.options;
    sim_.t_end = std::max(e.t_end, t_last);
    if (!(sim_.t_end > 0)) sim_.t_end = 1.0;  // only t = 0 samples: a nominal horizon
    sim_.t_out = t_out_;
    sim_.rtol = opt.rtol;
    sim_.atol = opt.atol;
    sim_.sens_error_control = opt.sens_error_control;
    sim_.sensitivities.clear();
  }

  const std::string& name() const { return name_; }
  int rows() const { return static_cast<int>(data_.size()); }
  const std::vector<double>& data() const { return data_; }
  double sigma_abs(int r) const { return sigma_abs_[r]; }
  double sigma_rel(int r) const { return sigma_rel_[r]; }
  long simulations() const { return sims_; }
  long sensitivity_solves() const { return sens_; }

  // Model at the rows for free parameters θ; dm/dθ (row-major rows x n) when `dm` != nullptr.
  void run(const double* theta, std::vector<double>& m, std::vector<double>* dm) {
    const int n = space_.size();
    Flowsheet& fs = *scene_.flowsheet;
    for (int k = 0; k < n; ++k) fs.set_param(space_.names[k], clamp_p(k, space_.to_p(k, theta[k])));
    if (!dm || opt_.jacobian == JacobianMethod::kCentralDifferences) {
      SimOptions o = sim_;
      extract(simulate(fs, o), m, nullptr);
      ++sims_;
      if (dm) central_differences(theta, *dm);
      return;
    }
    // One failed sensitivity solve must not end a calibration: retried once with smaller steps, then replaced by
    // central differences of plain simulations (which only throw when the model itself fails at θ).
    SimOptions o = sim_;
    o.sensitivities = space_.names;
    SimResult res;
    try {
      res = sensitivity_solve(o);
    } catch (const SolverError&) {
      ++retries_;
      SimOptions smaller = o;
      smaller.rtol = std::max(o.rtol / 10, 1e-14);
      smaller.atol = o.atol / 10;
      smaller.max_step = o.max_step > 0 ? std::min(o.max_step, o.t_end / 200) : o.t_end / 200;
      try {
        res = sensitivity_solve(smaller);
      } catch (const SolverError&) {
        SimOptions plain = sim_;
        extract(simulate(fs, plain), m, nullptr);
        ++sims_;
        central_differences(theta, *dm);
        return;
      }
    }
    extract(res, m, dm);
    for (int r = 0; r < rows(); ++r)
      for (int k = 0; k < n; ++k) (*dm)[size_t(r) * n + k] *= space_.dp_dtheta(k, theta[k]);
  }

  long retries() const { return retries_; }

 private:
  struct Obs {
    const Observation* src = nullptr;
    bool state = false;
    int index = 0;
    std::vector<int> samples, time_index;
  };

  double clamp_p(int k, double p) const { return std::min(std::max(p, space_.lower[k]), space_.upper[k]); }

  SimResult sensitivity_solve(const SimOptions& o) {
    ++sims_, ++sens_;
    if (calibration_testing::fail_sensitivity_solve && calibration_testing::fail_sensitivity_solve(name_))
      throw SolverError("experiment '" + name_ + "': sensitivity solve failed (test)", 0.0, "", 0.0);
    return simulate(*scene_.flowsheet, o);
  }

  // dm/dθ by central differences in θ (one-sided at a bound): 2 plain simulations per free parameter. The
  // flowsheet holds the parameters of θ before and after.
  void central_differences(const double* theta, std::vector<double>& dm) {
    const int n = space_.size();
    Flowsheet& fs = *scene_.flowsheet;
    SimOptions o = sim_;
    dm.assign(size_t(rows()) * n, 0.0);
    std::vector<double> mp, mm;
    for (int k = 0; k < n; ++k) {
      const double h =
          opt_.fd_step * (space_.transform[k] == Transform::kLog ? 1.0 : std::max(std::abs(theta[k]), 1.0));
      const double hi = std::min(theta[k] + h, space_.theta_upper(k)),
                   lo = std::max(theta[k] - h, space_.theta_lower(k));
      for (int side = 0; side < 2; ++side) {
        fs.set_param(space_.names[k], clamp_p(k, space_.to_p(k, side == 0 ? hi : lo)));
        extract(simulate(fs, o), side == 0 ? mp : mm, nullptr);
        ++sims_;
      }
      fs.set_param(space_.names[k], clamp_p(k, space_.to_p(k, theta[k])));
      for (int r = 0; r < rows(); ++r) dm[size_t(r) * n + k] = (mp[r] - mm[r]) / (hi - lo);
    }
  }

  void extract(const SimResult& r, std::vector<double>& m, std::vector<double>* dm) {
    const int n = space_.size();
    const size_t ns = r.state_names.size(), no = r.output_names.size();
    m.assign(rows(), 0.0);
    std::vector<double> dz;
    if (dm) {
      dm->assign(size_t(rows()) * n, 0.0);
      if (any_output_) {
        dz = output_sensitivities(*scene_.flowsheet, r);
      }
    }
    int row = 0;
    for (const auto& ob : obs_)
      for (size_t j = 0; j < ob.samples.size(); ++j, ++row) {
        const size_t it = ob.time_index[j];
        m[row] = ob.state ? r.y[it * ns + ob.index] : r.outputs[it * no + ob.index];
        if (!std::isfinite(m[row]))
          throw SolverError(
              "experiment '" + name_ + "': " + ob.src->name + " is not finite at t = " + std::to_string(r.t[it]) + " s",
              r.t[it], ob.src->name, 0.0);
        if (!dm) continue;
        for (int k = 0; k < n; ++k)
          (*dm)[size_t(row) * n + k] =
              ob.state ? r.sens[(it * n + k) * ns + ob.index] : dz[(it * n + k) * no + ob.index];
      }
  }

  Scene scene_;
  const Space& space_;
  const CalibrationOptions& opt_;
  std::string name_;
  std::vector<Obs> obs_;
  std::vector<double> data_, sigma_abs_, sigma_rel_, t_out_;
  SimOptions sim_;
  bool any_output_ = false;
  long sims_ = 0, sens_ = 0, retries_ = 0;
};

// The weighted residuals of one experiment; the residual block of Ceres.
class ExperimentCost : public ceres::CostFunction {
 public:
  ExperimentCost(ExperimentModel* model, int n, SigmaBasis basis) : model_(model), n_(n), basis_(basis) {
    set_num_residuals(model->rows());
    mutable_parameter_block_sizes()->push_back(n);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    try {
      compute(parameters[0], residuals, jacobians && jacobians[0] ? jacobians[0] : nullptr);
      return true;
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(error_mutex_);
      last_error_ = model_->name() + ": " + e.what();
      return false;
    }
  }

  // r = (m - d) / σ and, if J != nullptr, dr/dθ row-major. σ is fixed by the first evaluation (and by
  // reweight()): the loss is a fixed least-squares function between reweighting passes.
  void compute(const double* theta, double* r, double* J) const {
    std::vector<double> m, dm;
    model_->run(theta, m, J ? &dm : nullptr);
    const int rows = model_->rows();
    if (sigma_.empty()) sigma_ = sigma_at(m);
    weigh(m, J ? &dm : nullptr, r, J);
    if (J) {
      last_theta_.assign(theta, theta + n_);
      last_m_ = std::move(m);
      last_dm_ = std::move(dm);
      last_r_.assign(r, r + rows);
      last_J_.assign(J, J + size_t(rows) * n_);
    }
  }

  // Residuals and Jacobian at θ, from the last Jacobian evaluation if it was there.
  void at(const double* theta, std::vector<double>& r, std::vector<double>& J) const {
    if (!cached(theta)) {
      r.resize(model_->rows());
      J.resize(size_t(model_->rows()) * n_);
      compute(theta, r.data(), J.data());
    }
    r = last_r_, J = last_J_;
  }

  // SigmaBasis::kModel: σ_rel |m| at the last Jacobian point (which must be `theta`); rescales the cached
  // residuals and Jacobian to the new weights. Returns the largest relative change of a σ.
  double reweight(const double* theta) const {
    if (basis_ != SigmaBasis::kModel || !cached(theta)) return 0.0;
    const std::vector<double> s = sigma_at(last_m_);
    double change = 0.0;
    for (size_t i = 0; i < s.size(); ++i) change = std::max(change, std::abs(s[i] / sigma_[i] - 1.0));
    sigma_ = s;
    weigh(last_m_, &last_dm_, last_r_.data(), last_J_.data());
    return change;
  }

  const std::vector<double>& sigma() const { return sigma_; }
  void set_sigma(const std::vector<double>& s) { sigma_ = s; }

  std::string last_error() const {
    std::lock_guard<std::mutex> lock(error_mutex_);
    return last_error_;
  }
  ExperimentModel& model() const { return *model_; }

 private:
  ExperimentModel* model_;
  int n_;
  SigmaBasis basis_;
  bool cached(const double* theta) const {
    return last_theta_.size() == size_t(n_) && std::equal(last_theta_.begin(), last_theta_.end(), theta);
  }
  std::vector<double> sigma_at(const std::vector<double>& m) const {
    const auto& d = model_->data();
    std::vector<double> s(m.size());
    for (size_t i = 0; i < m.size(); ++i) {
      const double base = basis_ == SigmaBasis::kModel ? m[i] : d[i];
      s[i] = model_->sigma_abs(i) > 0 ? model_->sigma_abs(i) : model_->sigma_rel(i) * std::max(std::abs(base), 1e-300);
    }
    return s;
  }
  void weigh(const std::vector<double>& m, const std::vector<double>* dm, double* r, double* J) const {
    const auto& d = model_->data();
    for (size_t i = 0; i < m.size(); ++i) r[i] = (m[i] - d[i]) / sigma_[i];
    if (J)
      for (size_t i = 0; i < m.size(); ++i)
        for (int k = 0; k < n_; ++k) J[i * n_ + k] = (*dm)[i * n_ + k] / sigma_[i];
  }

  mutable std::vector<double> sigma_, last_theta_, last_m_, last_dm_, last_r_, last_J_;
  mutable std::mutex error_mutex_;
  mutable std::string last_error_;
};

// Everything of one stage: the models, their costs, and the Ceres solve.
struct StageRun {
  Space space;
  std::vector<std::unique_ptr<ExperimentModel>> models;
  std::vector<std::unique_ptr<ExperimentCost>> costs;
  std::vector<std::string> observables;

  StageRun(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps, const Stage& stage,
           const CalibrationOptions& opt, const std::map<std::string, double>& fixed)
      : space(make_space(*scene.flowsheet, stage)), observables(stage.observables) {
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

  long rows() const {
    long n = 0;
    for (const auto& m : models) n += m->rows();
    return n;
  }
  long simulations() const {
    long n = 0;
    for (const auto& m : models) n += m->simulations();
    return n;
  }
  long sensitivity_solves() const {
    long n = 0;
    for (const auto& m : models) n += m->sensitivity_solves();
    return n;
  }
  long sensitivity_retries() const {
    long n = 0;
    for (const auto& m : models) n += m->retries();
    return n;
  }

  // All residuals and the Jacobian (rows stacked by experiment) at θ.
  void evaluate(const std::vector<double>& theta, std::vector<double>& r, std::vector<double>* J, int threads) {
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

  ceres::Solver::Summary solve(std::vector<double>& theta, const CalibrationOptions& opt, int max_iterations) {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
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
    so.num_threads = opt.num_threads;
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
    std::string why;
    if (!so.IsValid(&why)) throw ConfigError("Ceres options: " + why);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    return summary;
  }

  double reweight(const std::vector<double>& theta) {
    double change = 0.0;
    for (auto& c : costs) change = std::max(change, c->reweight(theta.data()));
    return change;
  }
  std::vector<std::vector<double>> sigmas() const {
    std::vector<std::vector<double>> v;
    for (const auto& c : costs) v.push_back(c->sigma());
    return v;
  }
  void set_sigmas(const std::vector<std::vector<double>>& v) {
    for (size_t i = 0; i < costs.size() && i < v.size(); ++i) costs[i]->set_sigma(v[i]);
  }

  std::string first_error() const {
    for (const auto& c : costs)
      if (!c->last_error().empty()) return c->last_error();
    return "";
  }
};

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

double half_sum_squares(const std::vector<double>& r) {
  double c = 0;
  for (double v : r) c += v * v;
  return 0.5 * c;
}

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

// Runs one stage from `params` (updated with the estimates); statistics at the optimum if `statistics`.
StageResult run_stage(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                      const Stage& stage, const CalibrationOptions& opt, std::map<std::string, double>& params,
                      bool statistics, int max_iterations, const std::vector<std::vector<double>>* sigmas = nullptr,
                      std::vector<std::vector<double>>* sigmas_out = nullptr) {
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
  // Gradient Jᵀr and curvature (JᵀJ)_kk at the estimate; flat: χ² would change by less than flat_delta_chi2 with
  // θ_k anywhere within its bounds (to second order), so nothing the stage watches responds to it here.
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
  res.sensitivity_retries = run.sensitivity_retries();

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
  if (statistics) {
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
  res.simulations = run.simulations();
  res.sensitivity_solves = run.sensitivity_solves();
  res.wall_time_s = seconds_since(t0);
  if (sigmas_out) *sigmas_out = run.sigmas();
  return res;
}

// Δχ² profile of the loss over one free parameter of `stage`, the others re-optimized (warm-started outward).
// `lowest` (with its Δχ² in `lowest_dchi`) receives the parameters of the profile point of lowest cost when it is
// below `*lowest_dchi`: a profile that finds a lower cost than the estimate's shows the stage stopped short.
Profile profile_parameter(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                          const Stage& stage, const CalibrationOptions& opt,
                          const std::map<std::string, double>& optimum, const StageResult& at, int which,
                          const std::vector<std::vector<double>>& sigmas, std::map<std::string, double>& lowest,
                          double& lowest_dchi) {
  const Estimate& e = at.estimates[which];
  Profile pr;
  pr.name = e.name;
  const bool log_like = e.transform == Transform::kLog || e.logarithmic;
  const double lo_th = e.transform == Transform::kLog ? std::log(e.lower) : e.lower;
  const double hi_th = e.transform == Transform::kLog ? std::log(e.upper) : e.upper;
  const double reach = opt.profile_max_offset * (log_like ? 1.0 : std::max(std::abs(e.theta), 1e-300));
  const double two_se = std::isfinite(e.se_theta) ? 2 * e.se_theta : std::numeric_limits<double>::infinity();
  Stage sub = stage;
  sub.free.erase(sub.free.begin() + which);
  CalibrationOptions o = opt;
  o.profile = false;
  std::vector<std::pair<double, double>> pts{{e.theta, 0.0}};  // (θ, Δχ²)
  double dchi_2se[2] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  const auto to_p = [&](double th) { return e.transform == Transform::kLog ? std::exp(th) : th; };
  for (int side = -1; side <= 1; side += 2) {
    std::vector<double> offs;
    for (int j = opt.profile_max_points - 1; j >= 0; --j) offs.push_back(reach / std::pow(2.0, j));
    if (two_se < reach) offs.push_back(two_se);
    std::sort(offs.begin(), offs.end());
    offs.erase(std::unique(offs.begin(), offs.end()), offs.end());
    std::map<std::string, double> p = optimum;
    bool crossed = false;
    for (double off : offs) {
      double th = e.theta + side * off;
      const bool clipped = side < 0 ? th <= lo_th : th >= hi_th;
      if (clipped) th = side < 0 ? lo_th : hi_th;
      p[e.name] = to_p(th);
      double cost;
      try {
        if (sub.free.empty()) {
          StageRun run(scene, reg, exps, stage, o, p);
          run.set_sigmas(sigmas);
          std::vector<double> r, thv{th};
          run.evaluate(thv, r, nullptr, o.num_threads);
          cost = half_sum_squares(r);
          pr.simulations += run.simulations();
        } else {
          const StageResult sr = run_stage(scene, reg, exps, sub, o, p, false, std::min(o.max_iterations, 20), &sigmas);
          cost = sr.cost;
          pr.simulations += sr.simulations;
          pr.sensitivity_solves += sr.sensitivity_solves;
        }
      } catch (const SolverError&) {  // the model fails out there: the profile ends on this side
        break;
      } catch (const CalibrationError&) {
        break;
      }
      const double dchi = 2 * (cost - at.cost);
      if (dchi < lowest_dchi) lowest_dchi = dchi, lowest = p;
      pts.push_back({th, dchi});
      if (off == two_se) dchi_2se[(side + 1) / 2] = dchi;
      if (dchi > opt.profile_delta_chi2 && off >= std::min(two_se, reach)) {
        crossed = true;
        break;
      }
      if (clipped) break;
    }
    (side < 0 ? pr.bounded_below : pr.bounded_above) = crossed;
  }
  std::sort(pts.begin(), pts.end());
  for (const auto& [th, d] : pts) pr.values.push_back(to_p(th)), pr.delta_chi2.push_back(d);
  // Crossings of the threshold, linear in θ between profile points.
  const double thr = opt.profile_delta_chi2;
  size_t iopt = 0;
  while (iopt + 1 < pts.size() && pts[iopt].first != e.theta) ++iopt;
  pr.lower_95 = pr.values.front(), pr.upper_95 = pr.values.back();
  for (size_t i = iopt; i > 0; --i)
    if (pts[i - 1].second > thr) {
      const double f = (thr - pts[i].second) / (pts[i - 1].second - pts[i].second);
      pr.lower_95 = to_p(pts[i].first + f * (pts[i - 1].first - pts[i].first));
      break;
    }
  for (size_t i = iopt; i + 1 < pts.size(); ++i)
    if (pts[i + 1].second > thr) {
      const double f = (thr - pts[i].second) / (pts[i + 1].second - pts[i].second);
      pr.upper_95 = to_p(pts[i].first + f * (pts[i + 1].first - pts[i].first));
      break;
    }
  pr.linear_trustworthy = true;
  for (double d : dchi_2se)
    if (!(d > 2.0 && d < 8.0)) pr.linear_trustworthy = false;
  pr.verdict = !(pr.bounded_below && pr.bounded_above) ? "unidentifiable"
               : pr.linear_trustworthy                 ? "identifiable"
                                                       : "nonlinear";
  return pr;
}

}  // namespace

// ---------------------------------------------------------------- public API

void check_experiments(const Flowsheet& fs, const std::vector<Experiment>& exps) {
  validate_experiments(exps);
  std::set<std::string> names;
  for (const auto& e : exps) {
    const std::string w = "experiment '" + e.name + "'";
    if (!names.insert(e.name).second) throw ConfigError(w + " is given twice");
    for (const auto& [k, v] : e.settings) {
      int id;
      try {
        id = fs.param_id(k);
      } catch (const ConfigError& x) {
        throw ConfigError(w + ": setting " + x.what());
      }
      const ParamSpec& spec = fs.param_spec(id);
      const auto [lo, hi] = fs.bounds(id);
      if (const int src = fs.link_source(id); src >= 0)
        throw ConfigError(w + ": setting " + k + ": it follows " + fs.qualified_name(src) +
                          " by a link of the scene; set " + fs.qualified_name(src) + " instead");
      if (fs.has_input(id))
        throw ConfigError(w + ": setting " + k + ": it is driven by a time-dependent input of the scene (inputs: " + k +
                          "), which would replace the value; remove the input from the scene");
      if (!(v >= lo && v <= hi))
        throw ConfigError(
            violation(w + ": setting " + k, v, spec.unit, fmt_num(lo) + " <= " + spec.name + " <= " + fmt_num(hi)));
    }
    for (const auto& o : e.observations) {
      try {
        observable_unit(fs, o.name);
      } catch (const ConfigError& x) {
        throw ConfigError(w + ": observation " + x.what());
      }
    }
  }
}

CalibrationResult calibrate(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                            const std::vector<Stage>& stages, const CalibrationOptions& opt,
                            const std::map<std::string, double>& start) {
  opt.validate();
  check_experiments(*scene.flowsheet, exps);
  const auto t0 = Clock::now();
  if (stages.empty()) throw ConfigError("calibrate: no stages");
  if (exps.empty()) throw ConfigError("calibrate: no experiments");
  const Flowsheet& fs = *scene.flowsheet;
  CalibrationResult out;
  for (const auto& [k, v] : start) {
    fs.param_id(k);
    out.parameters[k] = v;
  }
  // A start value outside the bounds of a stage that frees it is bad input (not clipped silently).
  for (const auto& st : stages) {
    const Space sp = make_space(fs, st);
    for (int k = 0; k < sp.size(); ++k) {
      const auto it = start.find(sp.names[k]);
      if (it == start.end()) continue;
      if (!(it->second >= sp.lower[k] && it->second <= sp.upper[k]))
        throw ConfigError(violation("start." + sp.names[k], it->second, fs.param_spec(fs.param_id(sp.names[k])).unit,
                                    fmt(sp.lower[k], 12) + " <= " + sp.names[k] + " <= " + fmt(sp.upper[k], 12) +
                                        " (bounds of stage '" + st.name + "')"));
    }
  }
  for (const auto& st : stages)
    for (const auto& f : st.free)
      if (!out.parameters.count(f.name)) out.parameters[f.name] = fs.param(f.name);
  for (size_t s = 0; s < stages.size(); ++s) {
    const bool last = s + 1 == stages.size();
    const Stage& stage = stages[s];
    std::vector<std::vector<double>> sigmas;
    StageResult r = run_stage(scene, reg, exps, stage, opt, out.parameters, true, opt.max_iterations, nullptr, &sigmas);
    long extra_sims = 0, extra_sens = 0;  // scans, profiles and runs a restart replaced
    // Restarts from a lower point of the loss: a scan over the bounds of a parameter the loss is flat in at the
    // estimate (the start may lie in a flat region), or a profile point of the last stage below the estimate.
    const auto restart_from = [&](std::map<std::string, double> from, const std::string& why) {
      std::vector<std::vector<double>> sig;
      const double old_cost = r.cost;
      StageResult again = run_stage(scene, reg, exps, stage, opt, from, true, opt.max_iterations, nullptr, &sig);
      if (!(again.cost < old_cost)) {  // weights differ between runs: only an actual improvement replaces it
        extra_sims += again.simulations, extra_sens += again.sensitivity_solves;
        r.notes.push_back(why + "; the restart ended at a cost of " + fmt(again.cost, 6) + ", no lower: kept");
        return false;
      }
      extra_sims += r.simulations, extra_sens += r.sensitivity_solves;
      for (const auto& p : r.profiles) extra_sims += p.simulations, extra_sens += p.sensitivity_solves;
      again.notes = r.notes;
      again.restarts = r.restarts + 1;
      again.sensitivity_retries += r.sensitivity_retries;
      again.notes.push_back(why + "; restarted from there: cost " + fmt(old_cost, 6) + " -> " + fmt(again.cost, 6) +
                            " (Δχ² = " + fmt(2 * (old_cost - again.cost), 3) + ")");
      r = std::move(again);
      sigmas = std::move(sig);
      out.parameters = std::move(from);
      return true;
    };
    const auto unit_of = [&](const std::string& name) { return fs.param_spec(fs.param_id(name)).unit; };
    while (!r.flat.empty() && opt.flat_scan_points > 0 && r.restarts < opt.max_restarts) {
      // The scan: the lowest point, and the edge of the flat region (the scan point nearest the estimate, in units
      // of the span, where the loss responds), from where the stage's descent can find a narrow valley the scan's
      // spacing misses.
      std::string best_name, edge_name;
      double best_value = 0, best_cost = r.cost - 0.5 * opt.restart_delta_chi2, edge_value = 0, edge_distance = 2;
      for (const auto& name : r.flat) {
        const Space sp = make_space(fs, stage);
        const int k = static_cast<int>(std::find(sp.names.begin(), sp.names.end(), name) - sp.names.begin());
        StageRun run(scene, reg, exps, stage, opt, out.parameters);
        run.set_sigmas(sigmas);
        std::vector<double> th = start_theta(sp, out.parameters), res;
        const double at = th[k], span = sp.theta_upper(k) - sp.theta_lower(k);
        for (int j = 0; j < opt.flat_scan_points; ++j) {
          th[k] = sp.theta_lower(k) + span * j / (opt.flat_scan_points - 1);
          try {
            run.evaluate(th, res, nullptr, opt.num_threads);
          } catch (const SolverError&) {  // the model fails there: not a point to restart from
            continue;
          }
          const double c = half_sum_squares(res);
          if (c < best_cost) best_cost = c, best_name = name, best_value = sp.to_p(k, th[k]);
          if (std::abs(c - r.cost) > 0.5 * opt.restart_delta_chi2 && std::abs(th[k] - at) / span < edge_distance)
            edge_distance = std::abs(th[k] - at) / span, edge_name = name, edge_value = sp.to_p(k, th[k]);
        }
        extra_sims += run.simulations();
      }
      std::map<std::string, double> from = out.parameters;
      std::string why;
      if (!best_name.empty()) {
        why = "the loss was flat in " + best_name + " at " + fmt(out.parameters.at(best_name)) + " " +
              unit_of(best_name) + " (nothing the stage watches responds to it there); a scan over its bounds found " +
              "a cost lower by Δχ² = " + fmt(2 * (r.cost - best_cost), 3) + " at " + fmt(best_value) + " " +
              unit_of(best_name);
        from[best_name] = best_value;
      } else if (!edge_name.empty()) {
        why = "the loss was flat in " + edge_name + " at " + fmt(out.parameters.at(edge_name)) + " " +
              unit_of(edge_name) + " (nothing the stage watches responds to it there); a scan over its bounds " +
              "found it responding from " + fmt(edge_value) + " " + unit_of(edge_name) + " on";
        from[edge_name] = edge_value;
      } else {
        break;  // flat across the bounds: the data of the stage do not determine it
      }
      if (!restart_from(from, why)) break;
    }
    if (last && opt.profile) {
      while (true) {
        std::map<std::string, double> lowest;
        double lowest_dchi = -opt.restart_delta_chi2;
        r.profiles.clear();
        for (size_t k = 0; k < r.estimates.size(); ++k) {
          if (r.estimates[k].flag.empty()) continue;
          Profile p = profile_parameter(scene, reg, exps, stage, opt, out.parameters, r, static_cast<int>(k), sigmas,
                                        lowest, lowest_dchi);
          r.profiles.push_back(std::move(p));
        }
        if (lowest.empty() || r.restarts >= opt.max_restarts) break;
        std::string moved;
        for (const auto& e : r.estimates)
          if (lowest.count(e.name) && lowest.at(e.name) != e.value)
            moved += (moved.empty() ? "" : ", ") + e.name + " = " + fmt(lowest.at(e.name)) + " " + unit_of(e.name);
        if (!restart_from(lowest, "a profile found a cost lower than the estimate's by Δχ² = " + fmt(-lowest_dchi, 3) +
                                      " (at " + moved + ")"))
          break;
      }
      for (auto& p : r.profiles) {
        const auto it =
            std::find_if(r.estimates.begin(), r.estimates.end(), [&](const Estimate& e) { return e.name == p.name; });
        Estimate& e = *it;
        e.identifiable = p.verdict != "unidentifiable" && std::isfinite(e.se);
        e.flag += "; profile: " + p.verdict + " (Δχ² < " + fmt(opt.profile_delta_chi2, 3) + " over [" +
                  fmt(p.lower_95) + ", " + fmt(p.upper_95) + "]" + (p.bounded_below ? "" : ", open below") +
                  (p.bounded_above ? "" : ", open above") + ")";
      }
    }
    // What the user must know about this stage.
    const std::string w = "stage '" + r.name + "': ";
    for (const auto& name : r.flat)
      r.notes.push_back("the loss is flat in " + name + " at its estimate " + fmt(out.parameters.at(name)) + " " +
                        unit_of(name) +
                        (opt.flat_scan_points > 0 ? " and a scan over its bounds found no lower cost" : "") +
                        ": the data of this stage do not determine it from here (try other starts or bounds)");
    if (!r.moved) {
      std::string names;
      for (const auto& e : r.estimates) names += (names.empty() ? "" : ", ") + e.name;
      r.notes.push_back(
          "no free parameter moved from its start (" + names + ")" +
          (r.flat.empty() ? ": the start was already the optimum" : ": the start lies in a flat region of the loss"));
    }
    if (r.sensitivity_retries > 0)
      r.notes.push_back(std::to_string(r.sensitivity_retries) +
                        " sensitivity solves failed and were retried with smaller steps or replaced by central "
                        "differences");
    for (const auto& n : r.notes)
      if (n.rfind("no free parameter moved", 0) != 0 || !r.flat.empty()) out.warnings.push_back(w + n);
    // USER_SUCCESS is the small-change callback above: converged by this calibration's own criterion
    if (r.termination != "CONVERGENCE" && r.termination != "USER_SUCCESS" && out.status == "ok") {
      out.status = "no_convergence";
      out.message = "stage '" + r.name + "': " + r.message;
    }
    r.simulations += extra_sims;
    r.sensitivity_solves += extra_sens;
    out.simulations += r.simulations;
    out.sensitivity_solves += r.sensitivity_solves;
    for (const auto& p : r.profiles) out.simulations += p.simulations, out.sensitivity_solves += p.sensitivity_solves;
    out.stages.push_back(std::move(r));
  }
  if (const auto unused = unused_observations(exps, stages); !unused.empty()) {
    std::string list;
    for (const auto& u : unused) list += (list.empty() ? "" : ", ") + u;
    out.warnings.push_back("data that no stage uses: " + list +
                           "; add them to a stage's observables (a stage without observables uses all) or leave them "
                           "out of the experiments");
  }
  out.wall_time_s = seconds_since(t0);
  return out;
}

std::vector<std::string> unused_observations(const std::vector<Experiment>& exps, const std::vector<Stage>& stages) {
  std::set<std::string> used;
  for (const auto& st : stages) {
    if (st.observables.empty()) return {};  // a stage that watches everything
    used.insert(st.observables.begin(), st.observables.end());
  }
  std::map<std::string, std::pair<std::vector<std::string>, long>> unused;  // name -> (experiments, samples)
  for (const auto& e : exps)
    for (const auto& o : e.observations) {
      if (used.count(o.name)) continue;
      long n = 0;
      for (double v : o.value) n += std::isfinite(v);
      if (n == 0) continue;
      auto& [names, samples] = unused[o.name];
      if (names.empty() || names.back() != e.name) names.push_back(e.name);
      samples += n;
    }
  std::vector<std::string> out;
  for (const auto& [name, what] : unused) {
    std::string list;
    for (size_t i = 0; i < what.first.size() && i < 4; ++i) list += (i ? ", " : "") + what.first[i];
    if (what.first.size() > 4) list += ", ...";
    out.push_back(name + " (experiment" + (what.first.size() == 1 ? " " : "s ") + list + "; " +
                  std::to_string(what.second) + " samples)");
  }
  return out;
}

std::string CalibrationResult::brief() const {
  std::ostringstream os;
  os << "calibration " << status << ": " << stages.size() << " stage" << (stages.size() == 1 ? "" : "s");
  if (!stages.empty())
    os << ", final cost " << fmt(stages.back().cost, 6) << " (reduced chi2 " << fmt(stages.back().chi2_reduced, 3)
       << ")";
  os << ", " << simulations << " simulations (" << sensitivity_solves << " with sensitivities), " << fmt(wall_time_s, 3)
     << " s";
  std::string flagged;
  if (!stages.empty())
    for (const auto& e : stages.back().estimates)
      if (!e.identifiable) flagged += (flagged.empty() ? "" : ", ") + e.name;
  if (!flagged.empty()) os << "; unidentifiable: " << flagged;
  if (!warnings.empty()) os << "; " << warnings.size() << " warning" << (warnings.size() == 1 ? "" : "s");
  return os.str();
}

std::string CalibrationResult::full_report() const {
  std::ostringstream os;
  os << brief() << "\n";
  if (!message.empty()) os << message << "\n";
  for (const auto& w : warnings) os << "warning: " << w << "\n";
  os << "\nstage                         iter   cost start     cost end  chi2_red  sims  sens   time_s  jacobian\n";
  for (const auto& s : stages)
    os << std::left << std::setw(28) << s.name << std::right << std::setw(6) << s.iterations << std::setw(13)
       << fmt(s.initial_cost, 6) << std::setw(13) << fmt(s.cost, 6) << std::setw(10) << fmt(s.chi2_reduced, 3)
       << std::setw(6) << s.simulations << std::setw(6) << s.sensitivity_solves << std::setw(9) << fmt(s.wall_time_s, 3)
       << "  " << s.jacobian_method << " (" << s.termination << ")\n";
  for (const auto& s : stages) {
    os << "\n[" << s.name << "] observables:";
    if (s.observables.empty()) os << " all";
    for (const auto& o : s.observables) os << " " << o;
    os << "\nparameter                  start         estimate      std.error     rel.se   transform  identifiable\n";
    for (const auto& e : s.estimates)
      os << std::left << std::setw(22) << e.name << std::right << std::setw(14) << fmt(e.start, 6) << std::setw(14)
         << fmt(e.value, 6) << std::setw(14) << fmt(e.se, 4) << std::setw(11) << fmt(e.rel_se, 3) << std::setw(11)
         << to_string(e.transform) << "  " << (e.identifiable ? "yes" : "NO")
         << (e.flag.empty() ? "" : "  [" + e.flag + "]") << "\n";
    const size_t n = s.estimates.size();
    if (!s.correlation.empty()) {
      os << "correlation:\n";
      for (size_t i = 0; i < n; ++i) {
        os << "  " << std::left << std::setw(22) << s.estimates[i].name << std::right;
        for (size_t k = 0; k < n; ++k)
          os << std::setw(8) << std::fixed << std::setprecision(3) << s.correlation[i * n + k];
        os.unsetf(std::ios::fixed);
        os << "\n";
      }
    }
    for (const auto& n : s.notes) os << "note: " << n << "\n";
    for (const auto& p : s.profiles) {
      os << "profile of " << p.name << " (" << p.verdict << "):";
      for (size_t i = 0; i < p.values.size(); ++i) os << " " << fmt(p.values[i]) << ":" << fmt(p.delta_chi2[i], 3);
      os << "\n";
    }
  }
  return os.str();
}

std::vector<Prediction> predict(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                                const std::map<std::string, double>& params, const CalibrationOptions& opt) {
  opt.validate();
  check_experiments(*scene.flowsheet, exps);
  std::vector<std::vector<Prediction>> per(exps.size());
  parallel_for(static_cast<int>(exps.size()), opt.num_threads, [&](int i) {
    const Experiment& e = exps[i];
    Scene s = clone_scene(scene, reg);
    Flowsheet& fs = *s.flowsheet;
    for (const auto& [k, v] : params) fs.set_param(k, v);
    for (const auto& [k, v] : e.settings) fs.set_param(k, v);
    std::set<double> times;
    double t_last = 0;
    for (const auto& o : e.observations)
      for (double t : o.t) times.insert(t), t_last = std::max(t_last, t);
    if (times.empty()) return;
    SimOptions so = s.options;
    so.t_out.assign(times.begin(), times.end());
    so.t_end = std::max({e.t_end, t_last, 1e-9});
    so.rtol = opt.rtol;
    so.atol = opt.atol;
    so.sensitivities.clear();
    const SimResult r = simulate(fs, so);
    const auto outs = fs.output_names();
    const auto states = fs.state_names();
    const size_t ns = states.size(), no = outs.size();
    for (const auto& o : e.observations) {
      Prediction p;
      p.experiment = e.name;
      p.observable = o.name;
      auto io = std::find(outs.begin(), outs.end(), o.name);
      auto is = std::find(states.begin(), states.end(), o.name);
      if (io == outs.end() && is == states.end()) observable_unit(fs, o.name);
      for (size_t j = 0; j < o.t.size(); ++j) {
        const size_t it = std::lower_bound(so.t_out.begin(), so.t_out.end(), o.t[j]) - so.t_out.begin();
        const double m =
            io != outs.end() ? r.outputs[it * no + (io - outs.begin())] : r.y[it * ns + (is - states.begin())];
        p.t.push_back(o.t[j]);
        p.data.push_back(o.value[j]);
        p.model.push_back(m);
        p.sigma.push_back(o.sigma_abs > 0
                              ? o.sigma_abs
                              : o.sigma_rel * std::abs(opt.sigma_basis == SigmaBasis::kModel ? m : o.value[j]));
      }
      per[i].push_back(std::move(p));
    }
  });
  std::vector<Prediction> all;
  for (auto& v : per)
    for (auto& p : v) all.push_back(std::move(p));
  return all;
}

std::vector<FitStatistics> fit_statistics(const std::vector<Prediction>& preds) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::pair<double, double>>> by;
  for (const auto& p : preds) {
    if (!by.count(p.observable)) order.push_back(p.observable);
    auto& v = by[p.observable];
    for (size_t i = 0; i < p.data.size(); ++i)
      if (std::isfinite(p.data[i]) && std::isfinite(p.model[i])) v.push_back({p.data[i], p.model[i]});
  }
  std::vector<FitStatistics> out;
  for (const auto& name : order) {
    const auto& v = by[name];
    FitStatistics f;
    f.observable = name;
    f.n = static_cast<long>(v.size());
    if (v.empty()) {
      f.r2 = f.rmse = f.mean_abs_rel = std::numeric_limits<double>::quiet_NaN();
      out.push_back(f);
      continue;
    }
    double mean = 0;
    for (const auto& [d, m] : v) mean += d;
    mean /= v.size();
    double ss_res = 0, ss_tot = 0, rel = 0;
    for (const auto& [d, m] : v) {
      ss_res += (d - m) * (d - m);
      ss_tot += (d - mean) * (d - mean);
      rel += std::abs(m - d) / std::max(std::abs(d), 1e-300);
    }
    f.r2 = ss_tot > 0 ? 1 - ss_res / ss_tot : std::numeric_limits<double>::quiet_NaN();
    f.rmse = std::sqrt(ss_res / v.size());
    f.mean_abs_rel = rel / v.size();
    out.push_back(f);
  }
  return out;
}

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
    validate_experiments(exps);
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
std::vector<double> StageProblem::theta0() const { return start_theta(impl_->run->space, impl_->start); }
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
