// Scenes, parameters, inputs and simulation. Arguments are converted at the edge; the GIL is released for solves.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <tuple>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"
#include "granuflow/scene.hpp"
#include "granuflow/simulator.hpp"
#include "interrupt_poll.hpp"
#include "result_arrays.hpp"
#include "sweep_batch.hpp"
#include "units/registry.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

double value_for(const Scene& s, const std::string& name, const py::handle& v) {
  if (py::isinstance<py::str>(v))
    return parse_param_value(*s.flowsheet, name, v.cast<std::string>(), "parameter " + name);
  // True would silently become 1.0: a flag is never a parameter value.
  if (py::isinstance<py::bool_>(v))
    throw ConfigError("parameter " + name + " = " + std::string(py::str(v)) +
                      ": expected a number (SI) or a string with a unit, e.g. '60 degC', not a bool");
  try {
    return v.cast<double>();
  } catch (const py::cast_error&) {
    throw ConfigError("parameter " + name + " = " + std::string(py::repr(v)) +
                      ": expected a number (SI) or a string with a unit, e.g. '60 degC'");
  }
}

py::dict spec_dict(const ParamSpec& p, double value, bool input) {
  return py::dict("unit"_a = p.unit, "value"_a = value, "default"_a = p.value, "lower"_a = p.lower, "upper"_a = p.upper,
                  "description"_a = p.description, "source"_a = p.source, "input"_a = input);
}

// What each reported output means (aligned with output_names): role, quantity (balances), class (size distribution).
py::list output_roles(const Flowsheet& fs) {
  static const char* names[] = {"value",         "balance_in", "balance_out",    "balance_hold",
                                "size_diameter", "size_mass",  "regularization", "grid_end"};
  py::list out;
  for (const auto& u : fs.units())
    for (const auto& o : u.spec.outputs())
      out.append(py::make_tuple(names[static_cast<int>(o.role)], o.quantity, o.cls, u.name));
  return out;
}

py::dict simulate(Scene& s, std::optional<double> t_end, std::optional<std::vector<double>> t_out,
                  std::optional<int> n_out, std::optional<double> rtol, std::optional<double> atol,
                  std::vector<std::string> sensitivities, std::optional<std::string> linear_solver,
                  std::optional<long> max_steps, std::optional<std::string> method, bool names,
                  std::optional<std::vector<double>> checkpoints, std::string checkpoint_dir, std::string restart) {
  RunOverrides ov;
  ov.t_end = t_end, ov.t_out = std::move(t_out), ov.n_out = n_out, ov.rtol = rtol, ov.atol = atol;
  ov.linear_solver = std::move(linear_solver), ov.max_steps = max_steps, ov.method = std::move(method);
  SimOptions o = run_options(s, ov);
  o.sensitivities = std::move(sensitivities);
  if (checkpoints) o.checkpoints = *checkpoints;
  o.checkpoint_dir = std::move(checkpoint_dir), o.restart_file = std::move(restart);
  validate_as(o, "SimOptions.", "simulate(): ");
  SimResult r;
  try {
    const CoreCall call;
    r = granuflow::simulate(*s.flowsheet, o);
  } catch (const ConfigError& e) {  // found at run time (unit checks, structure): name the scene file as well
    throw ConfigError(runtime_config_message(s, e.what()));
  }
  const auto nt = static_cast<py::ssize_t>(r.t.size());
  const auto ns = static_cast<py::ssize_t>(r.state_names.size());
  const auto no = static_cast<py::ssize_t>(r.output_names.size());
  const auto np = static_cast<py::ssize_t>(r.sens_params.size());
  py::dict stats(
      "steps"_a = r.stats.steps, "residuals"_a = r.stats.residuals, "jacobians"_a = r.stats.jacobians,
      "linear_setups"_a = r.stats.linear_setups, "nonlinear_iterations"_a = r.stats.nonlinear_iterations,
      "error_test_failures"_a = r.stats.error_test_failures, "nonlinear_failures"_a = r.stats.nonlinear_failures,
      "reinits"_a = r.stats.reinits, "newton_starts"_a = r.stats.newton_starts,
      "calcic_starts"_a = r.stats.calcic_starts, "states"_a = r.stats.states,
      "explicit_states"_a = r.stats.explicit_states, "quadratures"_a = r.stats.quadratures,
      "linear_solver"_a = r.stats.linear_solver, "linear_iterations"_a = r.stats.linear_iterations,
      "preconditioner_setups"_a = r.stats.preconditioner_setups, "linear_failures"_a = r.stats.linear_failures,
      "method"_a = r.stats.method, "method_reason"_a = r.stats.method_reason);
  py::dict out(
      "t"_a = result_array(std::move(r.t), {nt}), "y"_a = result_array(std::move(r.y), {nt, ns}),
      "yp"_a = result_array(std::move(r.yp), {nt, ns}), "outputs"_a = result_array(std::move(r.outputs), {nt, no}),
      "output_sens"_a = result_array(std::move(r.output_sens), {nt, np, no}),
      "sens"_a = result_array(std::move(r.sens), {nt, np, ns}), "sens_params"_a = r.sens_params, "stats"_a = stats,
      "wall_time_s"_a = r.wall_time_s, "rtol"_a = o.rtol, "atol"_a = o.atol, "t_end"_a = o.t_end);
  // Recipes: the events that fired (with the phase each began) and the checkpoint files written.
  py::list events;
  for (const auto& e : r.events) events.append(py::dict("name"_a = e.name, "phase"_a = e.phase, "t"_a = e.t));
  out["events"] = events;
  out["checkpoint_files"] = r.checkpoint_files;
  out["checkpoints"] = o.checkpoints;
  // The names and roles depend on the flowsheet's structure only: a caller that keeps them asks once.
  if (names) {
    out["state_names"] = r.state_names;
    out["output_names"] = r.output_names;
    out["output_roles"] = output_roles(*s.flowsheet);
  }
  return out;
}

// Median wall time of one residual and of one Jacobian (dense below dense_limit states, else sparse) at the
// initial state, for the ns/state figures of the core benchmark; `classes_local`: the Jacobian a class-local Newton
// matrix asks for (DaeSystem::set_classes_local).
py::dict time_residual(Scene& s, int repeats, int dense_limit, bool classes_local) {
  py::gil_scoped_release release;
  DaeSystem sys(*s.flowsheet);
  sys.set_classes_local(classes_local);
  const int n = sys.size();
  std::vector<double> y, yp(n, 0.0), r(n);
  sys.initial_values(y);
  const bool dense = sys.inlined() || n <= dense_limit;  // inlined explicit units need the dense path
  std::vector<double> jd(dense ? size_t(n) * n : 0), js(dense ? 0 : sys.pattern().nnz());
  auto median = [&](auto&& f) {
    std::vector<double> t;
    for (int k = 0; k < repeats; ++k) {
      const auto a = std::chrono::steady_clock::now();
      int inner = 0;
      double el = 0;
      do {  // repeat fast calls until ~2 ms elapse, for timer resolution
        f();
        ++inner;
        el = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
      } while (el < 2e-3);
      t.push_back(el / inner);
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
  };
  const double tr = median([&] { sys.residual(0.0, y.data(), yp.data(), r.data()); });
  const double tj = median(
      [&] { sys.jacobian(0.0, y.data(), yp.data(), 1.0, dense ? jd.data() : nullptr, dense ? nullptr : js.data()); });
  py::gil_scoped_acquire acquire;
  return py::dict("states"_a = n, "residual_s"_a = tr, "jacobian_s"_a = tj, "dense"_a = dense,
                  "nnz"_a = dense ? long(n) * n : long(sys.pattern().nnz()));
}

}  // namespace

void register_flowsheet(py::module_& m) {
  const auto& reg = units::builtin();
  m.def(
      "unit_types",
      [&reg] {
        py::dict d;
        for (const auto& n : reg.names()) d[py::str(n)] = reg.description(n);
        return d;
      },
      "Built-in unit types and their descriptions.");
  m.def("to_si", &to_si, "value"_a, "unit"_a, "si_unit"_a, "where"_a = "value");

  py::class_<Scene>(m, "Scene")
      .def_readonly("path", &Scene::path)
      .def_readonly("name", &Scene::name)
      .def_readonly("description", &Scene::description)
      .def_readonly("material", &Scene::material)
      .def_readonly("material_unsupplied", &Scene::material_unsupplied)
      .def_readonly("summary_map", &Scene::summary)
      .def_readonly("extra_yaml", &Scene::extra_yaml)
      .def_readonly("sections_json", &Scene::sections_json)
      .def_readonly("text", &Scene::text)
      .def_property_readonly("t_end", [](const Scene& s) { return s.options.t_end; })
      .def_property_readonly("rtol", [](const Scene& s) { return s.options.rtol; })
      .def_property_readonly("atol", [](const Scene& s) { return s.options.atol; })
      .def_property_readonly("t_out", [](const Scene& s) { return s.options.t_out; })
      .def_property_readonly("checkpoints", [](const Scene& s) { return s.options.checkpoints; })
      .def_property_readonly("event_names",
                             [](const Scene& s) {
                               std::vector<std::string> v;
                               for (const auto& e : s.options.events) v.push_back(e.name);
                               return v;
                             })
      .def_property_readonly("n_out", [](const Scene& s) { return s.options.n_out; })
      .def("set_t_end",
           [](Scene& s, double t) {
             SimOptions o = s.options;
             o.t_end = t;
             o.t_out.clear();
             o.validate(true);  // "t_end = 0 s: violates t_end > 0", as the scene key
             s.options = o;
           })
      .def("clone", [&reg](const Scene& s) { return clone_scene(s, reg); })
      .def("param_names", [](const Scene& s) { return s.flowsheet->param_names(); })
      .def("state_names", [](const Scene& s) { return s.flowsheet->state_names(); })
      .def("output_names", [](const Scene& s) { return s.flowsheet->output_names(); })
      .def(
          "output_roles", [](const Scene& s) { return output_roles(*s.flowsheet); },
          "(role, quantity, class, unit) of every reported output, aligned with output_names()")
      .def("n_states", [](const Scene& s) { return s.flowsheet->n_states(); })
      .def(
          "get", [](const Scene& s, const std::string& name) { return s.flowsheet->param(name); }, "name"_a)
      .def(
          "set",
          [](Scene& s, const std::string& name, const py::handle& v) {
            s.flowsheet->set_param(name, value_for(s, name, v));
          },
          "name"_a, "value"_a)
      .def(
          "spec",
          [](const Scene& s, const std::string& name) {
            const int id = s.flowsheet->param_id(name);
            // lower/upper: the range the parameter may take (narrowed by parameters that follow it by a link).
            ParamSpec p = s.flowsheet->param_spec(id);
            std::tie(p.lower, p.upper) = s.flowsheet->bounds(id);
            return spec_dict(p, s.flowsheet->param_value(id), s.flowsheet->has_input(id));
          },
          "name"_a)
      .def(
          "set_input",
          [](Scene& s, const std::string& name, std::vector<double> times, const py::list& values,
             const std::string& interp) {
            std::vector<double> v;
            for (const auto& x : values) v.push_back(value_for(s, name, x));
            PiecewiseLinear::Interp i = PiecewiseLinear::Interp::kLinear;
            if (interp == "step")
              i = PiecewiseLinear::Interp::kStep;
            else if (interp != "linear")
              throw ConfigError("input " + name + ": interp '" + interp + "' is not one of linear, step");
            s.flowsheet->set_input(name, PiecewiseLinear(std::move(times), std::move(v), i, "input " + name));
          },
          "name"_a, "times"_a, "values"_a, "interp"_a = "linear")
      .def(
          "clear_input", [](Scene& s, const std::string& name) { s.flowsheet->clear_input(name); }, "name"_a,
          "Makes a parameter driven by a time-dependent input a constant again (its value before the input).")
      .def("unit_settings",
           [](const Scene& s) {
             py::dict d;
             for (const auto& u : s.flowsheet->units()) {
               if (u.owner >= 0) continue;  // a companion: part of its owner
               py::dict st;
               for (const auto& x : u.settings) st[py::str(x.name)] = setting_to_string(x.value);
               d[py::str(u.name)] = py::make_tuple(u.unit->type(), st);
             }
             return d;
           })
      .def("setting_specs",
           [](const Scene& s) {
             // unit -> [{name, type, value, choices, lower, upper, description}]: what a settings override is checked
             // against before the flowsheet is rebuilt (a name both a parameter and a setting)
             py::dict d;
             for (const auto& u : s.flowsheet->units()) {
               if (u.owner >= 0) continue;
               py::list st;
               for (const auto& x : u.settings)
                 st.append(py::dict("name"_a = x.name, "type"_a = to_string(x.type),
                                    "value"_a = setting_to_string(x.value), "choices"_a = x.choices,
                                    "lower"_a = x.lower, "upper"_a = x.upper, "description"_a = x.description));
               d[py::str(u.name)] = st;
             }
             return d;
           })
      .def("time_residual", &time_residual, "repeats"_a = 7, "dense_limit"_a = 400, "classes_local"_a = false)
      .def(
          "steady_state",
          [](Scene& s, double t, double ftol, long max_iterations, long max_pseudo_steps, bool stability) {
            SteadyOptions o;
            o.t = t;
            o.ftol = ftol;
            o.max_iterations = max_iterations;
            o.max_pseudo_steps = max_pseudo_steps;
            o.stability = stability;
            validate_as(o, "SteadyOptions.", "steady_state(): ");
            SteadyResult r;
            {
              const CoreCall call;
              r = solve_steady_state(*s.flowsheet, o);
            }
            const auto names = s.flowsheet->state_names();
            py::dict y;
            for (size_t i = 0; i < r.y.size(); ++i) y[py::str(names[i])] = r.y[i];
            const auto onames = s.flowsheet->output_names();
            py::dict out, flows;
            for (size_t i = 0; i < r.outputs.size(); ++i) out[py::str(onames[i])] = r.outputs[i];
            for (const auto& [q, f] : r.boundary_flows)
              flows[py::str(q)] = py::dict("in"_a = f.first, "out"_a = f.second);
            py::object stab = py::none();
            if (r.stability_known)
              stab = py::dict("max_real_eigenvalue"_a = r.max_real_eigenvalue, "imag_of_max"_a = r.imag_of_max,
                              "time_s"_a = r.stability_time_s);
            return py::dict("y"_a = y, "iterations"_a = r.iterations, "residual_norm"_a = r.residual_norm,
                            "method"_a = r.method, "pseudo_steps"_a = r.pseudo_steps, "conserved"_a = r.conserved,
                            "warnings"_a = r.warnings, "wall_time_s"_a = r.wall_time_s, "outputs"_a = out,
                            "boundary_flows"_a = flows, "stability"_a = stab);
          },
          py::kw_only(), "t"_a = 0.0, "ftol"_a = 1e-10, "max_iterations"_a = 200, "max_pseudo_steps"_a = 2000,
          "stability"_a = false)
      .def("simulate", &simulate, py::kw_only(), "t_end"_a = py::none(), "t_out"_a = py::none(), "n_out"_a = py::none(),
           "rtol"_a = py::none(), "atol"_a = py::none(), "sensitivities"_a = std::vector<std::string>{},
           "linear_solver"_a = py::none(), "max_steps"_a = py::none(), "method"_a = py::none(), "names"_a = true,
           "checkpoints"_a = py::none(), "checkpoint_dir"_a = "", "restart"_a = "");

  m.def(
      "load_scene", [&reg](const std::string& path) { return load_scene(path, reg); }, "path"_a);
  m.def(
      "check_yaml_text",
      [](const py::object& text, const std::string& label, const std::string& kind) {
        if (py::isinstance<py::bytes>(text)) return check_yaml_text(text.cast<std::string>(), label, kind);
        if (!py::isinstance<py::str>(text))
          throw ConfigError(label + ": expected the file's text (str or bytes), got " +
                            std::string(py::str(text.get_type().attr("__name__"))));
        const py::bytes b = text.attr("encode")("utf-8", "surrogatepass");
        check_yaml_text(b.cast<std::string>(), label, kind);
      },
      "text"_a, "label"_a, "kind"_a = "YAML file",
      "ConfigError (one line: file, line, column, what) unless the text is YAML granuflow can read safely: at most "
      "1 MiB of UTF-8, one document, at most 200000 values with aliases expanded, nesting at most 64, standard tags.");
  m.def(
      "load_scene_text",
      [&reg](const py::object& text, const std::string& label) {
        // Lone surrogates (from a file read with errors="surrogateescape") reach the loader as the bytes they
        // stand for, which it refuses naming line and column, instead of failing pybind's conversion.
        if (py::isinstance<py::bytes>(text)) return load_scene_text(text.cast<std::string>(), label, reg);
        if (!py::isinstance<py::str>(text))
          throw ConfigError(label + ": the scene must be given as text (str), got " +
                            std::string(py::str(text.get_type().attr("__name__"))));
        const py::bytes b = text.attr("encode")("utf-8", "surrogatepass");
        return load_scene_text(b.cast<std::string>(), label, reg);
      },
      "text"_a, "label"_a = "<text>");
  m.def(
      "splice_settings",
      [](const std::string& text, const std::string& unit, const std::vector<std::pair<std::string, std::string>>& kv,
         const std::string& label) {
        check_yaml_text(text, label, "scene");  // the limits of every YAML file before the parser builds it
        return splice_settings(text, unit, kv, label);
      },
      "text"_a, "unit"_a, "settings"_a, "label"_a,
      "The scene text with the settings of `unit` (particles, or units.<unit>) set to the given YAML flow values, "
      "all else byte for byte.");
}

}  // namespace granuflow::python
