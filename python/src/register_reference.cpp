// Read-only views of the registries for the user reference (granuflow units NAME, docs/units, docs/kernels): what a
// unit declares (ports, settings, parameters, states, outputs) and what a kernel declares, generated from the code
// itself so the documents cannot drift from it. Also the SI unit of every state and output of a built scene.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/materials.hpp"
#include "granuflow/quantity.hpp"
#include "granuflow/scene.hpp"
#include "kernels/registry.hpp"
#include "units/registry.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

py::dict param_dict(const ParamSpec& p) {
  return py::dict("name"_a = p.name, "unit"_a = p.unit, "default"_a = p.value, "lower"_a = p.lower, "upper"_a = p.upper,
                  "description"_a = p.description, "source"_a = p.source);
}

py::list settings_list(const std::vector<SettingSpec>& settings) {
  py::list out;
  for (const auto& s : settings)
    out.append(py::dict("name"_a = s.name, "type"_a = to_string(s.type), "default"_a = setting_to_string(s.value),
                        "choices"_a = s.choices, "lower"_a = s.lower, "upper"_a = s.upper,
                        "description"_a = s.description));
  return out;
}

const char* role_name(OutputRole r) {
  switch (r) {
    case OutputRole::kBalanceIn:
      return "balance in";
    case OutputRole::kBalanceOut:
      return "balance out";
    case OutputRole::kBalanceHold:
      return "balance hold-up";
    case OutputRole::kSizeDiameter:
      return "size distribution: pivot diameter";
    case OutputRole::kSizeMass:
      return "size distribution: class mass";
    case OutputRole::kRegularization:
      return "regularization count";
    case OutputRole::kGridEnd:
      return "mass fraction at the grid's end";
    default:
      return "value";
  }
}

// Declares a fresh unit of `type` with the given settings (defaults for the rest) and reports what it declared.
// Particle units read the flowsheet's particle system: a default one (paper 001's grid) is declared first.
py::dict unit_reference(const std::string& type, const std::map<std::string, std::string>& given) {
  const auto& reg = units::builtin();
  Flowsheet fs("unit_reference");
  if (type != "particles") fs.add_unit("particles", reg.create("particles"), Settings("particles", {}));
  fs.add_unit(type, reg.create(type, "unit_reference"), Settings("unit_reference(" + type + ").settings", given));
  const int self = fs.unit_index(type);
  const UnitSpec& spec = fs.units()[self].spec;
  std::vector<const UnitSpec*> comp_specs;  // the companions' declarations, in the order the unit declared them
  for (const auto& u : fs.units())
    if (u.owner == self) comp_specs.push_back(&u.spec);
  py::list ports, params, states, outputs;
  auto port_dict = [&](const std::string& name, const PortSpec& p) {
    ports.append(py::dict("name"_a = name, "kind"_a = to_string(p.kind), "direction"_a = to_string(p.dir),
                          "classes"_a = p.classes, "optional"_a = p.optional));
  };
  // A companion's outlet is the unit's port to a user (the hold-up port that feeds the companion is internal).
  const auto& comps = spec.companions();
  for (size_t k = 0; k < spec.ports().size(); ++k) {
    const auto c = std::find_if(comps.begin(), comps.end(), [&](const auto& x) { return x.from.i == int(k); });
    if (c == comps.end()) {
      port_dict(spec.ports()[k].name, spec.ports()[k]);
      continue;
    }
    for (const auto& p : comp_specs[c - comps.begin()]->ports())
      if (p.name == "out") port_dict(c->as, p);
  }
  for (const auto& p : spec.params()) params.append(param_dict(p));
  for (const auto& s : spec.states())
    states.append(py::dict("name"_a = s.name,
                           "kind"_a = s.kind == StateKind::Differential ? "differential" : "algebraic",
                           "unit"_a = s.unit, "scale"_a = s.scale));
  for (size_t k = 0; k < comps.size(); ++k)  // a companion's states carry the unit's name, computed inline
    for (const auto& s : comp_specs[k]->states())
      states.append(py::dict("name"_a = comps[k].name + "_" + s.name, "kind"_a = "algebraic, inline", "unit"_a = s.unit,
                             "scale"_a = s.scale));
  for (const auto& o : spec.outputs()) {
    bool quad = false;
    for (const auto& q : spec.quadratures()) quad = quad || q.output.i == &o - spec.outputs().data();
    outputs.append(py::dict("name"_a = o.name, "unit"_a = o.unit, "role"_a = role_name(o.role),
                            "quantity"_a = o.quantity, "integrated"_a = quad));
  }
  return py::dict("type"_a = type, "description"_a = reg.description(type), "explicit"_a = spec.is_explicit(),
                  "ports"_a = ports, "settings"_a = settings_list(fs.units()[self].settings), "params"_a = params,
                  "states"_a = states, "outputs"_a = outputs,
                  "particle_system"_a = spec.shared_params().empty() ? py::object(py::none())
                                                                     : py::object(py::str(spec.shared_params())));
}

py::dict needs_dict(const kernels::ClassNeeds& n) {
  return py::dict("number"_a = n.number, "moisture"_a = n.moisture, "spot_moisture"_a = n.spot_moisture,
                  "temperature"_a = n.temperature, "liquid_fraction"_a = n.liquid_fraction,
                  "wetted_fraction"_a = n.wetted_fraction);
}

template <class Base>
py::dict kernel_entry(const Registry<Base>& reg, const std::string& name) {
  py::dict d("name"_a = name, "description"_a = reg.description(name));
  if constexpr (std::is_base_of_v<kernels::KernelBase, Base>) {
    auto k = reg.create(name);
    Settings settings("kernel_reference(" + name + ").settings", {});
    try {
      k->declare(settings, "");
    } catch (const ConfigError& e) {
      // e.g. a kernel reading a data table that only a scene loads: its settings are listed as far as declared
      d["note"] = std::string(e.what());
    }
    py::list params;
    for (const auto& p : k->params()) params.append(param_dict(p));
    d["params"] = params;
    d["settings"] = settings_list(settings.declared());
    d["needs"] = needs_dict(k->needs());
    d["state_dependent"] = k->state_dependent();
  } else {
    d["params"] = py::list();
    d["settings"] = py::list();
  }
  return d;
}

template <class Base>
void add_family(py::dict& out, const char* family, const Registry<Base>& reg) {
  py::list l;
  for (const auto& n : reg.names()) l.append(kernel_entry(reg, n));
  out[family] = l;
}

py::dict kernel_reference() {
  py::dict out;
  kernels::registries().for_each([&](const char* family, const auto& reg) { add_family(out, family, reg); });
  return out;
}

}  // namespace

void register_reference(py::module_& m) {
  m.def("unit_reference", &unit_reference, "type"_a, "settings"_a = std::map<std::string, std::string>{},
        "What a unit of `type` declares with these settings (defaults for the rest): ports, settings, parameters, "
        "states and outputs.");
  m.def("kernel_reference", &kernel_reference,
        "Every registered kernel and scheme by family: description, parameters, settings, per-class needs.");
  m.def("known_si_units", &known_si_units, "The SI units parameters, states and outputs may declare.");
  m.def(
      "parse_quantity",
      [](const std::string& text) -> std::optional<std::pair<double, std::string>> {
        double v = 0.0;
        std::string unit;
        if (!parse_quantity(text, &v, &unit)) return std::nullopt;
        return std::make_pair(v, unit);
      },
      "text"_a,
      "(number, unit) of a quantity as scene files write it ('60 degC', '50um', '1e-3'), None where it does not "
      "start with a number: the one reading of the core and the Python edge.");
  m.def("setting_si_unit", &setting_si_unit, "description"_a,
        "The SI unit a real setting declares in its description (after a comma); '' for a plain number.");
  m.def(
      "material_catalogue",
      []() {
        py::list out;
        for (const Material& mat : material_catalogue()) {
          py::list props;
          for (const MaterialProperty& p : mat.properties)
            props.append(py::dict("name"_a = p.name, "value"_a = p.value, "unit"_a = p.unit, "source"_a = p.source,
                                  "description"_a = p.description,
                                  "applies_to"_a = particle_system_property(p.name) ? "particles" : "units"));
          out.append(py::dict("name"_a = mat.name, "description"_a = mat.description, "citation"_a = mat.citation,
                              "properties"_a = props));
        }
        return out;
      },
      "The catalogue of solid materials (name, description, citation, properties with value, SI unit, source).");
  m.def(
      "scene_units",
      [](const Scene& s) {
        py::dict d;
        for (const auto& u : s.flowsheet->units()) {
          for (const auto& x : u.spec.states()) d[py::str(u.state_prefix + x.name)] = x.unit;
          for (const auto& x : u.spec.outputs()) d[py::str(u.name + "." + x.name)] = x.unit;
        }
        return d;
      },
      "scene"_a, "SI unit of every state and reported output of a built scene.");
}

}  // namespace granuflow::python
