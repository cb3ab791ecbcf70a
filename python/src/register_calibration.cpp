// Calibration (Ceres): experiments, stages and options arrive as plain dicts/lists (built by
// granuflow.calibration), results leave as dicts of numpy arrays. The GIL is released while calibrating.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <type_traits>
#include <utility>
#include <vector>

#include "granuflow/calibration.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/output_sensitivity.hpp"
#include "granuflow/scene.hpp"
#include "interrupt_poll.hpp"
#include "units/registry.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

void check_keys(const py::dict& d, const std::set<std::string>& allowed, const std::string& where) {
  for (const auto& [k, v] : d) {
    const auto key = k.cast<std::string>();
    if (!allowed.count(key)) {
      std::string names;
      for (const auto& a : allowed) names += (names.empty() ? "" : ", ") + a;
      throw ConfigError(where + ": unknown key '" + key + "' (allowed: " + names + ")");
    }
  }
}

// A value converted for the core, or a ConfigError naming where it was and what it should have been (pybind's
// cast_error names neither).
template <class T>
T as(const py::handle& v, const std::string& where, const char* expected) {
  bool convertible = true;  // True is no number, and a str no list of numbers
  if constexpr (std::is_same_v<T, double> || std::is_same_v<T, std::vector<double>>)
    convertible = !py::isinstance<py::bool_>(v) && !py::isinstance<py::str>(v);
  if (convertible) {
    try {
      return v.cast<T>();
    } catch (const py::cast_error&) {
    }
  }
  std::string shown = py::repr(v).cast<std::string>();
  if (shown.size() > 60) shown = shown.substr(0, 60) + "...";
  throw ConfigError(where + " = " + shown + ": expected " + expected);
}

template <class T>
T required(const py::dict& d, const char* key, const std::string& where, const char* expected) {
  if (!d.contains(key)) throw ConfigError(where + ": missing required key '" + key + "'");
  return as<T>(d[key], where + "." + key, expected);
}

// Reads d[key] into out where present and not None.
template <class T>
void read_optional(const py::dict& d, const char* key, T& out, const std::string& where = "value") {
  if (d.contains(key) && !d[key].is_none()) out = as<T>(d[key], where + "." + key, "a number");
}

Experiment to_experiment(const py::dict& d) {
  check_keys(d, {"name", "settings", "t_end", "observations"}, "experiment");
  Experiment e;
  e.name = required<std::string>(d, "name", "experiment", "a name (str)");
  const std::string w = "experiment '" + e.name + "'";
  if (d.contains("settings"))
    for (const auto& [k, v] : as<py::dict>(d["settings"], w + ".settings", "a dict of unit.param -> SI value"))
      e.settings.emplace_back(as<std::string>(k, w + ".settings", "unit.param names (str)"),
                              as<double>(v, w + ".settings." + py::str(k).cast<std::string>(), "a number (SI)"));
  read_optional(d, "t_end", e.t_end, w);
  for (const auto& o : required<py::list>(d, "observations", w, "a list of observations")) {
    const auto od = as<py::dict>(o, w + ".observations[]", "a dict with name, t, value, sigma_abs or sigma_rel");
    const std::string where = w + ": observation";
    check_keys(od, {"name", "t", "value", "sigma_abs", "sigma_rel"}, where);
    Observation ob;
    ob.name = required<std::string>(od, "name", where, "a state or output name (str)");
    ob.t = required<std::vector<double>>(od, "t", where + " " + ob.name, "a list of times (s)");
    ob.value = required<std::vector<double>>(od, "value", where + " " + ob.name, "a list of numbers (SI)");
    read_optional(od, "sigma_abs", ob.sigma_abs, where + " " + ob.name);
    read_optional(od, "sigma_rel", ob.sigma_rel, where + " " + ob.name);
    // sizes, sigmas, times and values are checked in one place: the core's validate_experiments (calibrate,
    // predict, StageProblem), with the experiment and observation named
    e.observations.push_back(std::move(ob));
  }
  return e;
}

Stage to_stage(const py::dict& d) {
  check_keys(d, {"name", "free", "observables"}, "stage");
  Stage s;
  s.name = d["name"].cast<std::string>();
  for (const auto& f : d["free"].cast<py::list>()) {
    const auto fd = f.cast<py::dict>();
    check_keys(fd, {"name", "transform", "lower", "upper", "logarithmic"}, "stage '" + s.name + "': free parameter");
    FreeParameter p;
    p.name = fd["name"].cast<std::string>();
    if (fd.contains("transform") && !fd["transform"].is_none()) {
      try {
        p.transform = transform_from_string(fd["transform"].cast<std::string>());
      } catch (const ConfigError& e) {
        throw ConfigError("stage '" + s.name + "': free parameter " + p.name + ": " + e.what());
      }
    }
    read_optional(fd, "lower", p.lower);
    read_optional(fd, "upper", p.upper);
    read_optional(fd, "logarithmic", p.logarithmic);
    s.free.push_back(std::move(p));
  }
  read_optional(d, "observables", s.observables);
  return s;
}

// Sets one CalibrationOptions field from a Python value.
using OptionSetter = void (*)(CalibrationOptions&, const py::handle&);

// A name-valued option (a str); a cast_error saying which names otherwise.
std::string name_of(const py::handle& v, const char* names) {
  if (!py::isinstance<py::str>(v)) throw py::cast_error(names);
  return v.cast<std::string>();
}

// pybind converts True to 1 and 3 to true: a flag is no count and a count no flag, so a bool field takes only
// True/False and a number field no bool. The cast_error says what the field takes.
template <auto Member>
void set_field(CalibrationOptions& o, const py::handle& v) {
  using T = std::remove_reference_t<decltype(o.*Member)>;
  const char* expected = std::is_same_v<T, bool> ? "true or false"
                         : std::is_integral_v<T> ? "a whole number"
                                                 : "a number";
  if (py::isinstance<py::bool_>(v) != std::is_same_v<T, bool>) throw py::cast_error(expected);
  try {
    o.*Member = v.cast<T>();
  } catch (const py::cast_error&) {
    throw py::cast_error(expected);
  }
}

// The one list of option names: an unknown key is answered with it, in CalibrationOptions' order.
const std::vector<std::pair<std::string, OptionSetter>>& option_setters() {
  using O = CalibrationOptions;
  static const std::vector<std::pair<std::string, OptionSetter>> setters = {
      {"max_iterations", set_field<&O::max_iterations>},
      {"function_tolerance", set_field<&O::function_tolerance>},
      {"gradient_tolerance", set_field<&O::gradient_tolerance>},
      {"parameter_tolerance", set_field<&O::parameter_tolerance>},
      {"cost_change_tolerance", set_field<&O::cost_change_tolerance>},
      {"initial_trust_region_radius", set_field<&O::initial_trust_region_radius>},
      {"num_threads", set_field<&O::num_threads>},
      {"sigma_basis",
       [](O& o, const py::handle& v) { o.sigma_basis = sigma_basis_from_string(name_of(v, "model or data")); }},
      {"max_reweighting_passes", set_field<&O::max_reweighting_passes>},
      {"reweighting_tolerance", set_field<&O::reweighting_tolerance>},
      {"jacobian",
       [](O& o, const py::handle& v) {
         o.jacobian = jacobian_method_from_string(name_of(v, "sensitivities or central_differences"));
       }},
      {"fd_step", set_field<&O::fd_step>},
      {"rtol", set_field<&O::rtol>},
      {"atol", set_field<&O::atol>},
      {"sens_error_control", set_field<&O::sens_error_control>},
      {"scale_covariance", set_field<&O::scale_covariance>},
      {"rse_threshold", set_field<&O::rse_threshold>},
      {"correlation_threshold", set_field<&O::correlation_threshold>},
      {"profile", set_field<&O::profile>},
      {"profile_delta_chi2", set_field<&O::profile_delta_chi2>},
      {"profile_max_offset", set_field<&O::profile_max_offset>},
      {"profile_max_points", set_field<&O::profile_max_points>},
      {"flat_delta_chi2", set_field<&O::flat_delta_chi2>},
      {"flat_scan_points", set_field<&O::flat_scan_points>},
      {"restart_delta_chi2", set_field<&O::restart_delta_chi2>},
      {"max_restarts", set_field<&O::max_restarts>},
  };
  return setters;
}

CalibrationOptions to_options(const py::dict& d) {
  const auto& setters = option_setters();
  CalibrationOptions o;
  for (const auto& [kk, v] : d) {
    if (!py::isinstance<py::str>(kk))
      throw ConfigError("calibration option " + py::repr(kk).cast<std::string>().substr(0, 60) +
                        ": expected an option name (str)");
    const auto k = kk.cast<std::string>();
    const auto it = std::find_if(setters.begin(), setters.end(), [&](const auto& s) { return s.first == k; });
    if (it == setters.end()) {
      std::string names;
      for (const auto& s : setters) names += (names.empty() ? "" : ", ") + s.first;
      throw ConfigError("calibration option '" + k + "' is unknown (allowed: " + names + ")");
    }
    try {
      it->second(o, v);
    } catch (const py::cast_error& e) {
      std::string shown = py::repr(v).cast<std::string>();
      if (shown.size() > 60) shown = shown.substr(0, 57) + "...";
      throw ConfigError("calibration option " + k + " = " + shown + ": expected " + e.what() +
                        " (as the field of CalibrationOptions)");
    }
  }
  o.validate();
  return o;
}

py::array_t<double> square(const std::vector<double>& v, size_t n) {
  py::array_t<double> a({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(n)});
  if (v.size() == n * n)
    std::copy(v.begin(), v.end(), a.mutable_data());
  else
    std::fill(a.mutable_data(), a.mutable_data() + n * n, std::nan(""));
  return a;
}

py::dict stage_dict(const StageResult& s) {
  py::list est;
  for (const auto& e : s.estimates)
    est.append(py::dict("name"_a = e.name, "transform"_a = to_string(e.transform), "logarithmic"_a = e.logarithmic,
                        "start"_a = e.start, "value"_a = e.value, "theta"_a = e.theta, "se_theta"_a = e.se_theta,
                        "se"_a = e.se, "rel_se"_a = e.rel_se, "lower"_a = e.lower, "upper"_a = e.upper,
                        "at_bound"_a = e.at_bound, "identifiable"_a = e.identifiable, "flag"_a = e.flag));
  py::list prof;
  for (const auto& p : s.profiles)
    prof.append(py::dict("name"_a = p.name, "values"_a = p.values, "delta_chi2"_a = p.delta_chi2,
                         "lower_95"_a = p.lower_95, "upper_95"_a = p.upper_95, "bounded_below"_a = p.bounded_below,
                         "bounded_above"_a = p.bounded_above, "linear_trustworthy"_a = p.linear_trustworthy,
                         "simulations"_a = p.simulations, "sensitivity_solves"_a = p.sensitivity_solves,
                         "verdict"_a = p.verdict));
  const size_t n = s.estimates.size();
  return py::dict("name"_a = s.name, "observables"_a = s.observables, "estimates"_a = est,
                  "covariance"_a = square(s.covariance, n), "correlation"_a = square(s.correlation, n),
                  "iteration_costs"_a = s.iteration_costs, "initial_cost"_a = s.initial_cost, "cost"_a = s.cost,
                  "residuals"_a = s.residuals, "chi2_reduced"_a = s.chi2_reduced, "iterations"_a = s.iterations,
                  "passes"_a = s.passes, "weight_change"_a = s.weight_change, "simulations"_a = s.simulations,
                  "sensitivity_solves"_a = s.sensitivity_solves, "wall_time_s"_a = s.wall_time_s,
                  "jacobian_method"_a = s.jacobian_method, "termination"_a = s.termination, "message"_a = s.message,
                  "usable"_a = s.usable, "profiles"_a = prof, "gradient"_a = s.gradient, "curvature"_a = s.curvature,
                  "flat"_a = s.flat, "moved"_a = s.moved, "restarts"_a = s.restarts,
                  "sensitivity_retries"_a = s.sensitivity_retries, "notes"_a = s.notes);
}

std::vector<Experiment> to_experiments(const py::list& l) {
  std::vector<Experiment> v;
  for (const auto& e : l) v.push_back(to_experiment(e.cast<py::dict>()));
  return v;
}

std::vector<Stage> to_stages(const py::list& l) {
  std::vector<Stage> v;
  for (const auto& s : l) v.push_back(to_stage(s.cast<py::dict>()));
  return v;
}

// Residuals of one stage as a function of θ (tests, Jacobian checks).
class PyStageProblem {
 public:
  PyStageProblem(const Scene& scene, const py::list& exps, const py::dict& stage, const py::dict& options,
                 const std::map<std::string, double>& start)
      : p_(scene, units::builtin(), to_experiments(exps), to_stage(stage), to_options(options), start) {}
  py::tuple evaluate(const std::vector<double>& theta, bool jacobian) {
    std::vector<double> r, J;
    {
      const CoreCall call;
      p_.evaluate(theta, r, jacobian ? &J : nullptr);
    }
    py::array_t<double> ra(static_cast<py::ssize_t>(r.size()));
    std::copy(r.begin(), r.end(), ra.mutable_data());
    if (!jacobian) return py::make_tuple(ra, py::none());
    py::array_t<double> Ja({static_cast<py::ssize_t>(r.size()), static_cast<py::ssize_t>(theta.size())});
    std::copy(J.begin(), J.end(), Ja.mutable_data());
    return py::make_tuple(ra, Ja);
  }
  StageProblem p_;
};

}  // namespace

void register_calibration(py::module_& m) {
  m.def(
      "observable_unit", [](const Scene& s, const std::string& name) { return observable_unit(*s.flowsheet, name); },
      "scene"_a, "name"_a, "SI unit of a state or reported output; ConfigError listing valid names otherwise.");

  m.def(
      "check_calibration_options", [](const py::dict& options) { to_options(options); }, "options"_a,
      "ConfigError naming the field, the value and the rule if `options` are not valid CalibrationOptions.");
  m.def(
      "calibration_tolerances",
      [](const py::dict& options) {
        const CalibrationOptions o = to_options(options);
        return py::make_tuple(o.rtol, o.atol);
      },
      "options"_a, "(rtol, atol) the simulations of a calibration with these options use (defaults filled in).");

  m.def(
      "calibrate",
      [](const Scene& scene, const py::list& exps, const py::list& stages, const py::dict& options,
         const std::map<std::string, double>& start, const std::optional<py::function>& progress) {
        const auto ex = to_experiments(exps);
        const auto st = to_stages(stages);
        CalibrationOptions o = to_options(options);
        if (progress)
          o.progress = [&progress](const CalibrationProgress& p) {
            py::gil_scoped_acquire gil;
            try {
              (*progress)(p.stage, p.iteration, p.cost, p.simulations, p.sensitivity_solves);
            } catch (py::error_already_set& e) {  // an interrupt raised in the callback (Ctrl-C while it ran)
              if (!e.matches(PyExc_KeyboardInterrupt)) throw;
              e.restore();  // Python's KeyboardInterrupt stands; the stage ends at this iteration
              request_interrupt();
            }
          };
        CalibrationResult r;
        {
          const CoreCall call;
          r = calibrate(scene, units::builtin(), ex, st, o, start);
        }
        py::list sd;
        for (const auto& s : r.stages) sd.append(stage_dict(s));
        return py::dict("status"_a = r.status, "message"_a = r.message, "brief"_a = r.brief(),
                        "full_report"_a = r.full_report(), "parameters"_a = r.parameters,
                        "simulations"_a = r.simulations, "sensitivity_solves"_a = r.sensitivity_solves,
                        "wall_time_s"_a = r.wall_time_s, "stages"_a = sd, "warnings"_a = r.warnings);
      },
      "scene"_a, "experiments"_a, "stages"_a, "options"_a = py::dict(), "start"_a = std::map<std::string, double>{},
      "progress"_a = py::none(),
      "progress(stage, iteration, cost, simulations, sensitivity_solves): called after every Ceres iteration, on the "
      "calling thread with the GIL.");

  m.def(
      "predict",
      [](const Scene& scene, const py::list& exps, const std::map<std::string, double>& params,
         const py::dict& options) {
        const auto ex = to_experiments(exps);
        const CalibrationOptions o = to_options(options);
        std::vector<Prediction> p;
        {
          const CoreCall call;
          p = predict(scene, units::builtin(), ex, params, o);
        }
        py::list out;
        for (const auto& x : p)
          out.append(py::dict("experiment"_a = x.experiment, "observable"_a = x.observable, "t"_a = x.t,
                              "data"_a = x.data, "model"_a = x.model, "sigma"_a = x.sigma));
        return out;
      },
      "scene"_a, "experiments"_a, "params"_a = std::map<std::string, double>{}, "options"_a = py::dict());

  m.def(
      "output_sensitivities",
      [](Scene& s, double t_end, const std::vector<double>& t_out, const std::vector<std::string>& params) {
        SimOptions o = s.options;
        o.t_end = t_end;
        o.t_out = t_out;
        o.sensitivities = params;
        std::vector<double> dz;
        size_t no = 0;
        {
          const CoreCall call;
          const SimResult r = simulate(*s.flowsheet, o);
          dz = output_sensitivities(*s.flowsheet, r);
          no = r.output_names.size();
        }
        py::array_t<double> a({static_cast<py::ssize_t>(t_out.size()), static_cast<py::ssize_t>(params.size()),
                               static_cast<py::ssize_t>(no)});
        std::copy(dz.begin(), dz.end(), a.mutable_data());
        return a;
      },
      "scene"_a, "t_end"_a, "t_out"_a, "params"_a,
      "d(output)/d(param) [time, param, output] from one forward-sensitivity solve.");

  py::class_<PyStageProblem>(m, "StageProblem")
      .def(py::init<const Scene&, const py::list&, const py::dict&, const py::dict&,
                    const std::map<std::string, double>&>(),
           "scene"_a, "experiments"_a, "stage"_a, "options"_a = py::dict(), "start"_a = std::map<std::string, double>{})
      .def_property_readonly("num_parameters", [](const PyStageProblem& p) { return p.p_.num_parameters(); })
      .def_property_readonly("num_residuals", [](const PyStageProblem& p) { return p.p_.num_residuals(); })
      .def("theta0", [](const PyStageProblem& p) { return p.p_.theta0(); })
      .def("to_params", [](const PyStageProblem& p, const std::vector<double>& th) { return p.p_.to_params(th); })
      .def("to_theta", [](const PyStageProblem& p, const std::vector<double>& v) { return p.p_.to_theta(v); })
      .def("evaluate", &PyStageProblem::evaluate, "theta"_a, "jacobian"_a = true)
      .def_property_readonly("simulations", [](const PyStageProblem& p) { return p.p_.simulations(); })
      .def_property_readonly("sensitivity_solves", [](const PyStageProblem& p) { return p.p_.sensitivity_solves(); });
}

}  // namespace granuflow::python
