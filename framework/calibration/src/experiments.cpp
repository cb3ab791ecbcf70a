// The calibration's inputs: option and enum spellings, and the checks of experiments against a flowsheet before
// any simulation runs.
#include <cmath>
#include <map>
#include <set>

#include "calibration_internal.hpp"
#include "granuflow/errors.hpp"
#include "size_fraction.hpp"

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

std::string observable_unit(const Flowsheet& fs, const std::string& name) {
  if (calib::size_fraction(fs, name)) return "-";  // Q3 at a size: a fraction
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

namespace calib {

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

}  // namespace calib

namespace {

// A measured size or absolute temperature is positive and a measured mass is not negative: a sign slipped into a
// data file would otherwise be fitted as data.
void check_sign(const std::string& w, const Observation& o, const std::string& unit) {
  const bool positive = unit == "m" || unit == "K";
  if (!positive && unit != "kg") return;
  for (size_t i = 0; i < o.value.size(); ++i) {
    const double v = o.value[i];
    if (std::isnan(v) || (positive ? v > 0 : v >= 0)) continue;
    throw ConfigError(violation(
        w + ".value[" + std::to_string(i) + "] at t = " + fmt_num(o.t[i]) + " s", v, unit,
        positive ? "value > 0 (a measured " + std::string(unit == "m" ? "size" : "temperature") + "; NaN: not measured)"
                 : std::string("value >= 0 (a measured mass; NaN: not measured)")));
  }
}

}  // namespace

void check_experiments(const Flowsheet& fs, const std::vector<Experiment>& exps, bool measured) {
  calib::validate_experiments(exps);
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
      std::string unit;
      try {
        unit = observable_unit(fs, o.name);
      } catch (const ConfigError& x) {
        throw ConfigError(w + ": observation " + x.what());
      }
      if (measured) check_sign(w + ": observation " + o.name, o, unit);
      if (measured && calib::size_fraction(fs, o.name))
        for (size_t i = 0; i < o.value.size(); ++i)
          if (o.value[i] < 0 || o.value[i] > 1)
            throw ConfigError(violation(
                w + ": observation " + o.name + ".value[" + std::to_string(i) + "] at t = " + fmt_num(o.t[i]) + " s",
                o.value[i], "", "0 <= Q3 <= 1 (a fraction, not %; NaN: not measured)"));
    }
  }
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

}  // namespace granuflow
