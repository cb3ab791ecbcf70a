#include "events.hpp"

#include <algorithm>
#include <cmath>
#include <regex>
#include <set>

#include "events_settings.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"

namespace granuflow::detail {

namespace {

std::string scalar_text(const YAML::Node& n, const std::string& where) {
  if (!n.IsScalar()) throw ConfigError(where + ": expected a single value, not a list or mapping");
  return n.Scalar();
}

double value_in(const std::string& text, const std::string& si_unit, const std::string& where) {
  double v;
  std::string unit;
  if (!parse_quantity(text, &v, &unit) || !std::isfinite(v))
    throw ConfigError(where + " = '" + text + "': expected a number with an optional unit (SI unit: " + si_unit + ")");
  // A mass ratio (kg/kg) also takes a plain fraction or percentage: "bed.moisture < 1 %" means 1 wt%.
  if (si_unit == "kg/kg" && !unit.empty() && unit != "kg/kg") try {
      return to_si(v, unit, "-", where);
    } catch (const ConfigError&) {
    }
  return to_si(v, unit, si_unit, where);
}

// "bed.d50 >= 450 um": the quantity, the direction in which crossing the threshold makes the condition true.
void parse_when(const Flowsheet& fs, const std::string& text, const std::string& where, EventSpec& e) {
  static const std::regex re(R"(^\s*([A-Za-z_][A-Za-z0-9_.\[\]]*)\s*(>=|<=|>|<)\s*(.+?)\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw ConfigError(where + " = '" + text +
                      "': expected 'unit.quantity OP value [unit]' with OP one of >=, >, <=, < (e.g. 'bed.d50 >= "
                      "450 um')");
  e.when = text;
  e.quantity = m[1];
  const std::string op = m[2];
  e.direction = op[0] == '>' ? 1 : -1;
  const EventQuantity q = find_event_quantity(fs, e.quantity, where);
  e.threshold = value_in(m[3], q.unit, where + " (" + e.quantity + ")");
}

// "unit.setting": a setting the unit declares, switched by rebuilding the unit (events_settings.hpp); the new value and
// the layout it gives are checked here, so that a run never meets a switch it cannot make.
EventAction setting_action(const Flowsheet& fs, const Registry<Unit>& units, const std::string& target,
                           const std::string& text, const std::string& at) {
  const auto dot = target.find('.');
  int u = -1;
  for (size_t k = 0; k < fs.units().size() && dot != std::string::npos; ++k)
    if (fs.units()[k].name == target.substr(0, dot) && fs.units()[k].owner < 0) u = static_cast<int>(k);
  std::string setting;  // its name now: an event written with a deprecated spelling switches the same setting
  if (u >= 0)
    for (const auto& st : fs.units()[u].settings)
      if (st.name == target.substr(dot + 1) || st.old_name == target.substr(dot + 1)) setting = st.name;
  if (setting.empty())
    throw ConfigError(at +
                      ": neither a parameter nor a setting of the flowsheet (an event sets unit.param or "
                      "unit.setting; `granuflow describe` lists them)");
  EventAction a;
  a.target = target.substr(0, dot + 1) + setting, a.text = text;
  const std::string type = fs.units()[u].unit->type();
  const Registry<Unit>* reg = &units;
  a.make = [reg, type] { return reg->create(type); };
  rebuild_unit(fs, u, a, at);  // refuses a value or a layout the run cannot switch to
  return a;
}

void parse_do(const Flowsheet& fs, const Registry<Unit>& units, const YAML::Node& d, const std::string& where,
              EventSpec& e) {
  if (d.IsScalar()) {
    if (d.Scalar() != "stop") throw ConfigError(where + " = '" + d.Scalar() + "': expected stop or {set: {...}}");
    e.stop = true;
    return;
  }
  if (!d.IsMap()) throw ConfigError(where + ": expected stop or a mapping {set: {unit.param: value}, stop: true}");
  for (const auto& kv : d) {
    const std::string k = kv.first.Scalar();
    if (k == "stop") {
      const std::string v = scalar_text(kv.second, where + ".stop");
      if (v != "true" && v != "false") throw ConfigError(where + ".stop = '" + v + "': expected true or false");
      e.stop = v == "true";
    } else if (k == "set") {
      if (!kv.second.IsMap() || kv.second.size() == 0)
        throw ConfigError(where + ".set: expected a non-empty mapping of unit.param -> value");
      for (const auto& p : kv.second) {
        const std::string target = p.first.Scalar(), at = where + ".set." + target;
        const std::string text = scalar_text(p.second, at);
        const auto names = fs.param_names();
        if (std::find(names.begin(), names.end(), target) == names.end()) {
          e.set.push_back(setting_action(fs, units, target, text, at));
          continue;
        }
        const int id = fs.param_id(target);
        if (const int src = fs.link_source(id); src >= 0)
          throw ConfigError(at + ": follows " + fs.qualified_name(src) + " by a link; set " + fs.qualified_name(src) +
                            " instead");
        const double v = value_in(text, fs.param_spec(id).unit, at);
        const auto [lo, hi] = fs.bounds(id);
        if (!(v >= lo && v <= hi))
          throw ConfigError(violation(at, v, fs.param_spec(id).unit,
                                      fmt_num(lo) + " <= value <= " + fmt_num(hi) + " " + fs.param_spec(id).unit));
        e.set.push_back({target, v, text, {}});  // a parameter: nothing to make
      }
    } else {
      throw ConfigError(where + "." + k + ": unknown key (allowed: set, stop)");
    }
  }
  if (!e.stop && e.set.empty())
    throw ConfigError(where + ": an event must set a parameter or a setting, or stop the run");
}

}  // namespace

EventQuantity find_event_quantity(const Flowsheet& fs, const std::string& name, const std::string& where) {
  EventQuantity q;
  const auto states = fs.state_names();
  for (size_t i = 0; i < states.size(); ++i)
    if (states[i] == name) {
      q.state = static_cast<int>(i), q.unit = fs.state_spec(q.state).unit;
      return q;
    }
  int k = 0;
  for (const auto& u : fs.units()) {
    const auto& outs = u.spec.outputs();
    for (size_t j = 0; j < outs.size(); ++j, ++k) {
      if (u.name + "." + outs[j].name != name) continue;
      for (const auto& qs : u.spec.quadratures())
        if (qs.output.i == static_cast<int>(j))
          throw ConfigError(where + ": " + name +
                            " integrates a flow over time (a quadrature), which the root finding does not see; use a "
                            "state or another output");
      q.output = k, q.unit = outs[j].unit;
      return q;
    }
  }
  throw ConfigError(where + ": '" + name + "' is neither a state nor a reported output of the flowsheet " +
                    "(`granuflow describe` lists them)");
}

std::vector<EventSpec> load_events(const YAML::Node& node, const Flowsheet& fs, const std::string& label,
                                   const Registry<Unit>& units) {
  if (!node.IsSequence())
    throw ConfigError(label +
                      ": events: expected a list of {name, when, do} (e.g. [{name: stop_spray, when: "
                      "'bed.d50 >= 450 um', do: {set: {nozzle.mdot: 0 kg/s}}}])");
  std::vector<EventSpec> out;
  std::set<std::string> names;
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node& n = node[i];
    std::string at = label + ": events[" + std::to_string(i) + "]";
    if (!n.IsMap()) throw ConfigError(at + ": expected a mapping {name, when, do}");
    EventSpec e;
    if (!n["name"]) throw ConfigError(at + ": missing key 'name'");
    e.name = scalar_text(n["name"], at + ".name");
    at += " (" + e.name + ")";
    if (!names.insert(e.name).second) throw ConfigError(at + ".name: a second event of this name");
    for (const auto& kv : n) {
      const std::string k = kv.first.Scalar();
      if (k != "name" && k != "when" && k != "do" && k != "phase" && k != "after" && k != "repeat")
        throw ConfigError(at + "." + k + ": unknown key (allowed: name, when, do, phase, after, repeat)");
    }
    for (const char* k : {"when", "do"})
      if (!n[k]) throw ConfigError(at + ": missing key '" + k + "'");
    parse_when(fs, scalar_text(n["when"], at + ".when"), at + ".when", e);
    parse_do(fs, units, n["do"], at + ".do", e);
    if (n["phase"]) e.phase = scalar_text(n["phase"], at + ".phase");
    if (n["after"]) {
      e.after = scalar_text(n["after"], at + ".after");
      if (!names.count(e.after) || e.after == e.name)
        throw ConfigError(at + ".after = '" + e.after + "': not an event declared before this one");
    }
    if (n["repeat"]) {
      const std::string v = scalar_text(n["repeat"], at + ".repeat");
      if (v != "true" && v != "false") throw ConfigError(at + ".repeat = '" + v + "': expected true or false");
      e.repeat = v == "true";
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<double> load_checkpoints(const YAML::Node& node, const std::string& label) {
  if (!node.IsSequence() || node.size() == 0)
    throw ConfigError(label + ": checkpoints: expected a non-empty list of times (e.g. [10 min, 30 min])");
  std::vector<double> t;
  for (size_t i = 0; i < node.size(); ++i)
    t.push_back(value_in(scalar_text(node[i], label + ": checkpoints[" + std::to_string(i) + "]"), "s",
                         label + ": checkpoints[" + std::to_string(i) + "]"));
  return t;
}

void check_events(const Flowsheet& fs, const std::vector<EventSpec>& events, const std::vector<std::string>& sens) {
  for (const auto& e : events)
    for (const auto& a : e.set)
      for (const auto& p : sens)
        if (!a.is_setting() && fs.param_id(p) == fs.param_id(a.target))
          throw ConfigError("sensitivity parameter '" + p + "' is set by event '" + e.name +
                            "': its value after the event no longer depends on it; ask for another parameter");
}

}  // namespace granuflow::detail
