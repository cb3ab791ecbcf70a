#include "events_settings.hpp"

#include <cstdio>
#include <map>

#include "granuflow/errors.hpp"

namespace granuflow::detail {

std::string setting_text(const SettingSpec& s) {
  if (const auto* r = std::get_if<double>(&s.value)) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", *r);
    return buf;
  }
  return setting_to_string(s.value);
}

namespace {

// What differs between the layouts of two declarations of one unit; empty when the run can carry over its state.
std::string layout_difference(const UnitSpec& a, const UnitSpec& b) {
  auto names = [](const auto& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x.name;
    return s;
  };
  if (a.classes().n != b.classes().n || a.size_edges() != b.size_edges())
    return "it changes the size classes (" + std::to_string(a.classes().n) + " -> " + std::to_string(b.classes().n) +
           " classes)";
  if (a.states().size() != b.states().size())
    return "it changes the number of states (" + std::to_string(a.states().size()) + " -> " +
           std::to_string(b.states().size()) + ")";
  for (size_t i = 0; i < a.states().size(); ++i)
    if (a.states()[i].name != b.states()[i].name || a.states()[i].kind != b.states()[i].kind)
      return "it changes the states (" + a.states()[i].name + " -> " + b.states()[i].name + ")";
  if (names(a.params()) != names(b.params())) {
    std::string added, removed;
    auto missing = [](const auto& from, const auto& in, std::string& out) {
      for (const auto& p : from) {
        bool found = false;
        for (const auto& q : in) found = found || q.name == p.name;
        if (!found) out += (out.empty() ? "" : ", ") + p.name;
      }
    };
    missing(b.params(), a.params(), added), missing(a.params(), b.params(), removed);
    return "it changes the parameters (" + (added.empty() ? "" : "adds " + added) +
           (added.empty() || removed.empty() ? "" : "; ") + (removed.empty() ? "" : "removes " + removed) +
           (added.empty() && removed.empty() ? "their order" : "") + ")";
  }
  if (names(a.outputs()) != names(b.outputs()))
    return "it changes the reported outputs (" + std::to_string(a.outputs().size()) + " -> " +
           std::to_string(b.outputs().size()) + ")";
  if (names(a.quadratures()) != names(b.quadratures())) return "it changes the quadratures";
  if (a.ports().size() != b.ports().size()) return "it changes the ports";
  for (size_t i = 0; i < a.ports().size(); ++i) {
    const PortSpec &p = a.ports()[i], &q = b.ports()[i];
    if (p.name != q.name || p.kind != q.kind || p.dir != q.dir || p.classes != q.classes || p.grid != q.grid ||
        p.provided != q.provided || p.forwarded != q.forwarded)
      return "it changes port " + p.name;
  }
  if (a.companions().size() != b.companions().size() || a.shared_params() != b.shared_params() ||
      a.is_explicit() != b.is_explicit() || a.has_analytic_part() != b.has_analytic_part() ||
      a.analytic_complete() != b.analytic_complete() || a.has_preconditioner() != b.has_preconditioner() ||
      a.reductions() != b.reductions())
    return "it changes how the unit is solved (companions, explicit form, analytic Jacobian or reductions)";
  return "";
}

}  // namespace

RebuiltUnit rebuild_unit(const Flowsheet& fs, int u, const EventAction& a, const std::string& where) {
  const UnitInstance& inst = fs.units()[u];
  const std::string setting = a.target.substr(a.target.find('.') + 1);
  // Units that share this one's parameters (a particle system) were declared from its settings (the size grid):
  // they would keep the old ones.
  std::string readers;
  for (const auto& other : fs.units())
    if (other.shared == u) readers += (readers.empty() ? "" : ", ") + other.name;
  if (!readers.empty())
    throw ConfigError(where + " = '" + a.text + "': cannot change during a run, the units " + readers +
                      " were laid out from the settings of " + inst.name +
                      " (its size classes and components), so the run's state cannot be carried over");
  std::map<std::string, std::string> given;
  for (const auto& s : inst.settings) given[s.name] = setting_text(s);
  given[setting] = a.text;
  RebuiltUnit r;
  r.unit = a.make();
  UnitSpec spec;
  Settings st(where, given);
  st.attach(&fs);
  r.unit->declare(spec, st);
  st.attach(nullptr);
  r.settings = st.declared();
  if (const std::string why = layout_difference(inst.spec, spec); !why.empty())
    throw ConfigError(where + " = '" + a.text + "': cannot change during a run, " + why +
                      ", so the run's state cannot be carried over; an event may switch a setting only where the unit "
                      "keeps its states, parameters and outputs");
  return r;
}

}  // namespace granuflow::detail
