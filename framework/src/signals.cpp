// Resolution and checks of the signals units ask for (signals.hpp).
#include "granuflow/signals.hpp"

#include <cmath>
#include <tuple>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow {

namespace {

const SignalUnit* signals_of(const UnitInstance& u) { return dynamic_cast<const SignalUnit*>(u.unit.get()); }

// A request of unit `by`: (qualified parameter driven, its source, the setting that named the other side).
struct Request {
  std::string param, source, setting;
};

std::vector<Request> requests(const Flowsheet& fs) {
  std::vector<Request> v;
  for (const auto& u : fs.units()) {
    const SignalUnit* s = signals_of(u);
    if (!s) continue;
    for (const auto& r : s->reads())
      v.push_back({u.name + "." + u.spec.params()[r.param.i].name, r.source, u.name + "." + r.setting});
    for (const auto& w : s->writes())
      v.push_back({w.target, u.state_prefix + u.spec.states()[w.state.i].name, u.name + "." + w.setting});
  }
  return v;
}

int output_index(const UnitSpec& spec, const std::string& name) {
  for (size_t k = 0; k < spec.outputs().size(); ++k)
    if (spec.outputs()[k].name == name) return static_cast<int>(k);
  return -1;
}

bool is_quadrature(const UnitSpec& spec, int output) {
  for (const auto& q : spec.quadratures())
    if (q.output.i == output) return true;
  return false;
}

}  // namespace

std::string driven_by(const Flowsheet& fs, int id) {
  const std::string q = fs.qualified_name(id);
  for (const auto& r : requests(fs))
    if (r.param == q) return r.source + " (setting " + r.setting + ")";
  return "";
}

std::vector<Drive> resolve_drives(const Flowsheet& fs) {
  std::vector<Drive> drives;
  const auto& units = fs.units();
  for (const auto& r : requests(fs)) {
    auto fail = [&](const std::string& why) { throw ConfigError(r.setting + ": " + why); };
    if (r.param.empty() || r.source.empty() || r.source.back() == '.')
      fail("required (the controller's measured quantity and the parameter it sets, as unit.name)");
    Drive d;
    int id = -1;
    try {
      id = fs.param_id(r.param);
    } catch (const ConfigError& e) {
      fail(e.what());
    }
    std::tie(d.unit, d.param) = fs.param_location(id);
    d.label = r.param + " <- " + r.source + " (setting " + r.setting + ")";
    for (const auto& o : drives)
      if (o.unit == d.unit && o.param == d.param) fail(r.param + " is driven twice (" + o.label + ")");
    if (fs.has_input(id)) fail(r.param + " has a time-dependent input, which the controller would override");
    if (fs.link_source(id) >= 0 || !fs.linked_targets(id).empty())
      fail(r.param + " takes part in a link (links:); a driven parameter can neither follow nor be followed");
    for (const auto& u : units)
      if (u.shared == d.unit) fail(r.param + " belongs to the particle system other units read; it cannot be driven");
    // the source: a state (one column) or else an output (the columns of its unit)
    const auto dot = r.source.find('.');
    const int su = dot == std::string::npos ? -1 : [&] {
      for (size_t k = 0; k < units.size(); ++k)
        if (units[k].name == r.source.substr(0, dot)) return static_cast<int>(k);
      return -1;
    }();
    try {
      d.state = fs.state_id(r.source);
    } catch (const ConfigError&) {
      if (su >= 0) d.output = output_index(units[su].spec, r.source.substr(dot + 1));
      if (d.output < 0) fail("'" + r.source + "' is no state or output of the flowsheet");
      if (is_quadrature(units[su].spec, d.output))
        fail("'" + r.source + "' integrates a flow over time (a quadrature): the equations cannot read it");
      if (units[d.unit].spec.is_explicit() || units[d.unit].spec.classes().n > 0)
        fail(r.param + " belongs to an explicit unit or one with size classes, which can be driven by a state only");
      d.source_unit = su;
    }
    if (d.state >= 0 && units[fs.state_unit(d.state)].spec.is_explicit())
      fail("'" + r.source + "' is a state of an explicit unit (computed inline, after the drives by states)");
    if (d.source_unit == d.unit || (d.state >= 0 && fs.state_unit(d.state) == d.unit))
      fail(r.param + " would be driven by its own unit");
    drives.push_back(d);
  }
  for (const auto& d : drives)  // a measured unit's outputs are evaluated with its state-driven parameters only
    for (const auto& e : drives)
      if (d.source_unit >= 0 && e.unit == d.source_unit && e.source_unit >= 0)
        throw ConfigError(d.label + ": the unit measured is itself driven by an output (" + e.label + ")");
  return drives;
}

// Relative distance from its set point beyond which a held quantity misses it (the ideal level controller's smoothing
// keeps the bed within 1e-5 of M_set, a PI controller's integral brings the error to round-off).
constexpr double kSetPointTolerance = 1e-3;

std::vector<std::string> missed_set_points(const Flowsheet& fs, double t, const std::vector<double>& outputs) {
  std::vector<std::string> missed;
  size_t first = 0;  // the unit's first output
  for (size_t u = 0; u < fs.units().size(); ++u) {
    const UnitInstance& inst = fs.units()[u];
    if (const auto* h = dynamic_cast<const HoldsSetPoint*>(inst.unit.get())) {
      const std::vector<double> p = fs.run_params(static_cast<int>(u));
      for (const auto& sp : h->set_points()) {
        const auto& in = inst.inputs[sp.set_point.i];
        const double target = in ? (*in)(t) : p[sp.set_point.i];
        const double value = outputs.at(first + sp.value.i);
        const OutputSpec& o = inst.spec.outputs()[sp.value.i];
        const std::string unit = o.unit == "-" ? "" : " " + o.unit;
        if (std::abs(value - target) <= kSetPointTolerance * std::abs(target)) continue;
        missed.push_back("unit " + inst.name + " (" + inst.unit->type() + ") misses its set point: " + inst.name + "." +
                         o.name + " = " + fmt_num(value) + unit + ", set point " + inst.name + "." +
                         inst.spec.params()[sp.set_point.i].name + " = " + fmt_num(target) + unit +
                         " (its output at a limit, or nothing left to control)");
      }
    }
    first += inst.spec.outputs().size();
  }
  return missed;
}

}  // namespace granuflow
