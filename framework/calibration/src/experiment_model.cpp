#include "experiment_model.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "granuflow/errors.hpp"
#include "granuflow/output_sensitivity.hpp"

namespace granuflow {

namespace calibration_testing {
std::function<bool(const std::string&)> fail_sensitivity_solve;
}

namespace calib {

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

ExperimentModel::ExperimentModel(const Scene& scene, const Registry<Unit>& reg, const Experiment& e,
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
    if (auto q3 = size_fraction(fs, o.name)) {
      ob.q3 = static_cast<int>(q3_.size());
      q3_.push_back(std::move(*q3));
      any_output_ = true;
    } else if (it != outs.end()) {
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

void ExperimentModel::run(const double* theta, std::vector<double>& m, std::vector<double>* dm) {
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

SimResult ExperimentModel::sensitivity_solve(const SimOptions& o) {
  ++sims_, ++sens_;
  if (calibration_testing::fail_sensitivity_solve && calibration_testing::fail_sensitivity_solve(name_))
    throw SolverError("experiment '" + name_ + "': sensitivity solve failed (test)", 0.0, "", 0.0);
  return simulate(*scene_.flowsheet, o);
}

void ExperimentModel::central_differences(const double* theta, std::vector<double>& dm) {
  const int n = space_.size();
  Flowsheet& fs = *scene_.flowsheet;
  SimOptions o = sim_;
  dm.assign(size_t(rows()) * n, 0.0);
  std::vector<double> mp, mm;
  for (int k = 0; k < n; ++k) {
    const double h = opt_.fd_step * (space_.transform[k] == Transform::kLog ? 1.0 : std::max(std::abs(theta[k]), 1.0));
    const double hi = std::min(theta[k] + h, space_.theta_upper(k)), lo = std::max(theta[k] - h, space_.theta_lower(k));
    for (int side = 0; side < 2; ++side) {
      fs.set_param(space_.names[k], clamp_p(k, space_.to_p(k, side == 0 ? hi : lo)));
      extract(simulate(fs, o), side == 0 ? mp : mm, nullptr);
      ++sims_;
    }
    fs.set_param(space_.names[k], clamp_p(k, space_.to_p(k, theta[k])));
    for (int r = 0; r < rows(); ++r) dm[size_t(r) * n + k] = (mp[r] - mm[r]) / (hi - lo);
  }
}

void ExperimentModel::extract(const SimResult& r, std::vector<double>& m, std::vector<double>* dm) {
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
      if (ob.q3 >= 0) {
        q3_row(ob.q3, r, it, dz, m[row], dm ? &(*dm)[size_t(row) * n] : nullptr);
        continue;
      }
      m[row] = ob.state ? r.y[it * ns + ob.index] : r.outputs[it * no + ob.index];
      if (!std::isfinite(m[row]))
        throw SolverError(
            "experiment '" + name_ + "': " + ob.src->name + " is not finite at t = " + std::to_string(r.t[it]) + " s",
            r.t[it], ob.src->name, 0.0);
      if (!dm) continue;
      for (int k = 0; k < n; ++k)
        (*dm)[size_t(row) * n + k] = ob.state ? r.sens[(it * n + k) * ns + ob.index] : dz[(it * n + k) * no + ob.index];
    }
}

void ExperimentModel::q3_row(int k, const SimResult& r, size_t it, const std::vector<double>& dz, double& m,
                             double* dm) const {
  const SizeFraction& f = q3_[k];
  const int n = space_.size(), classes = static_cast<int>(f.w.size());
  const size_t no = r.output_names.size();
  std::vector<double> dq(classes);
  m = size_fraction_value(f, &r.outputs[it * no + f.first_output], dq.data());
  if (!std::isfinite(m))
    throw SolverError("experiment '" + name_ + "': " + f.unit +
                          " holds no particles at t = " + std::to_string(r.t[it]) +
                          " s, so it has no size distribution to compare with Q3(" + fmt_num(f.size) + " m)",
                      r.t[it], f.unit, 0.0);
  if (!dm) return;
  for (int p = 0; p < n; ++p) {
    double s = 0.0;
    for (int i = 0; i < classes; ++i) s += dq[i] * dz[(it * n + p) * no + f.first_output + i];
    dm[p] = s;
  }
}

}  // namespace calib
}  // namespace granuflow
