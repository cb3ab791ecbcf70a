#include "granuflow/flowsheet.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <set>
#include <sstream>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/renamed.hpp"
#include "granuflow/signals.hpp"

namespace granuflow {

void Flowsheet::add_unit(const std::string& name, std::unique_ptr<Unit> unit, Settings settings) {
  if (finalized_) throw std::logic_error("add_unit after finalize");
  if (name.empty() || name.find_first_of(".:") != std::string::npos)
    throw ConfigError("unit name '" + name + "': must be non-empty and contain no '.' or ':'");
  const std::string where = settings.where();
  add_instance(name, std::move(unit), std::move(settings));
  const int owner = static_cast<int>(units_.size()) - 1;
  const auto companions = units_[owner].spec.companions();  // a copy: units_ grows below
  for (const auto& c : companions) {
    const std::string cname = name + ":" + c.name;
    add_instance(cname, c.make(name), Settings(where + " (" + c.name + ")", {}));
    const int k = static_cast<int>(units_.size()) - 1;
    units_[k].owner = owner;
    units_[k].state_prefix = name + "." + c.name + "_";
    connect(name + "." + units_[owner].spec.ports()[c.from.i].name, cname + ".in");
    aliases_[{owner, c.as}] = split_port(cname + ".out");
  }
}

void Flowsheet::add_instance(const std::string& name, std::unique_ptr<Unit> unit, Settings settings) {
  for (const auto& u : units_)
    if (u.name == name) throw ConfigError("unit '" + name + "' is defined twice");
  UnitInstance inst;
  inst.name = name;
  inst.state_prefix = name + ".";
  inst.unit = std::move(unit);
  settings.attach(this);
  inst.unit->declare(inst.spec, settings);
  settings.check_all_used();  // attached: a setting given to the wrong unit names the unit it belongs to
  settings.attach(nullptr);
  if (!inst.spec.shared_params().empty()) {
    for (size_t k = 0; k < units_.size(); ++k)
      if (units_[k].name == inst.spec.shared_params()) inst.shared = static_cast<int>(k);
    if (inst.shared < 0) throw std::logic_error("unit '" + name + "' reads the parameters of an absent unit");
  }
  inst.settings = settings.declared();
  for (const auto& p : inst.spec.params()) inst.params.push_back(p.value);
  inst.inputs.resize(inst.params.size());
  inst.peers.assign(inst.spec.ports().size(), {-1, -1});
  units_.push_back(std::move(inst));
}

std::string Flowsheet::port_label(int u, int p) const {
  for (const auto& [key, target] : aliases_)
    if (target == std::make_pair(u, p)) return units_[key.first].name + "." + key.second;
  return units_[u].name + "." + units_[u].spec.ports()[p].name;
}

int Flowsheet::unit_index(const std::string& name) const {
  for (size_t i = 0; i < units_.size(); ++i)
    if (units_[i].name == name) return static_cast<int>(i);
  std::string allowed;
  for (const auto& u : units_)
    if (u.owner < 0) allowed += (allowed.empty() ? "" : ", ") + u.name;
  throw ConfigError("unknown unit '" + name + "' (units: " + allowed + ")");
}

std::pair<int, int> Flowsheet::split_port(const std::string& qualified) const {
  const auto dot = qualified.find('.');
  if (dot == std::string::npos) throw ConfigError("port '" + qualified + "': expected 'unit.port'");
  const int u = unit_index(qualified.substr(0, dot));
  const std::string port = qualified.substr(dot + 1);
  const auto& ports = units_[u].spec.ports();
  for (size_t p = 0; p < ports.size(); ++p)
    if (ports[p].name == port) return {u, static_cast<int>(p)};
  if (auto a = aliases_.find({u, port}); a != aliases_.end()) return a->second;
  std::string allowed;
  for (const auto& p : ports) allowed += (allowed.empty() ? "" : ", ") + p.name;
  for (const auto& [key, target] : aliases_)
    if (key.first == u) allowed += (allowed.empty() ? "" : ", ") + key.second;
  throw ConfigError("unit '" + units_[u].name + "' has no port '" + port +
                    "' (ports: " + (allowed.empty() ? "none" : allowed) + ")");
}

void Flowsheet::connect(const std::string& from, const std::string& to) {
  if (finalized_) throw std::logic_error("connect after finalize");
  const auto a = split_port(from), b = split_port(to);
  const PortSpec& pa = units_[a.first].spec.ports()[a.second];
  const PortSpec& pb = units_[b.first].spec.ports()[b.second];
  if (pa.dir == PortDir::In)
    throw ConfigError("connection " + from + " -> " + to + ": '" + from + "' is an inlet; a connection goes out -> in");
  if (pb.dir != PortDir::In)
    throw ConfigError("connection " + from + " -> " + to + ": '" + to + "' is an outlet; a connection goes out -> in");
  if (pa.kind != pb.kind)
    throw ConfigError("connection " + from + " -> " + to + ": stream kinds differ (" + to_string(pa.kind) + " vs " +
                      to_string(pb.kind) + ")");
  if (pa.classes != pb.classes)
    throw ConfigError("connection " + from + " -> " + to + ": size-class counts differ (" + std::to_string(pa.classes) +
                      " vs " + std::to_string(pb.classes) + ")");
  if (!pa.grid.empty() && !pb.grid.empty()) {
    for (size_t i = 0; i < pa.grid.size(); ++i)
      if (std::abs(pa.grid[i] - pb.grid[i]) > 1e-9 * pa.grid[i])
        throw ConfigError("connection " + from + " -> " + to + ": size grids differ (pivot " + std::to_string(i) +
                          ": " + fmt_num(pa.grid[i] * 1e6) + " um vs " + fmt_num(pb.grid[i] * 1e6) +
                          " um); give both units the same classes, d_min and d_max");
  }
  if (units_[b.first].peers[b.second].first >= 0) throw ConfigError("port " + to + " is connected twice");
  if (pa.dir == PortDir::Out && units_[a.first].peers[a.second].first >= 0)
    throw ConfigError("port " + from + " is connected twice (only a probe port may feed several inlets)");
  if (pa.dir == PortDir::Probe) {
    for (size_t f = 0; f < pa.provided.size(); ++f)
      if (pa.provided[f] < 0 && pa.forwarded[f].first < 0)
        throw std::logic_error("probe port " + from + " must provide every field");
  }
  units_[a.first].peers[a.second] = b;
  units_[b.first].peers[b.second] = a;
  connections_.push_back({a, b});
}

void Flowsheet::finalize() {
  if (finalized_) return;
  n_states_ = 0;
  state_owner_.clear();
  param_table_.clear();
  // Integrated states first, then those of explicit units, which a simulator may evaluate inline.
  n_explicit_ = 0;
  for (bool explicit_pass : {false, true})
    for (size_t u = 0; u < units_.size(); ++u) {
      if (units_[u].spec.is_explicit() != explicit_pass) continue;
      const int ns = static_cast<int>(units_[u].spec.states().size());
      units_[u].offset = n_states_;
      n_states_ += ns;
      if (explicit_pass) n_explicit_ += ns;
      state_owner_.insert(state_owner_.end(), ns, static_cast<int>(u));
    }
  for (size_t u = 0; u < units_.size(); ++u)
    for (size_t k = 0; k < units_[u].params.size(); ++k) param_table_.push_back({int(u), int(k)});
  n_quads_ = 0;
  for (auto& inst : units_) {
    inst.quad_offset = n_quads_;
    n_quads_ += static_cast<int>(inst.spec.quadratures().size());
  }
  // Every port field resolves to the global index of the state behind it: provided by this side, by the peer, or
  // forwarded from one of the unit's inlets (followed through any chain of pass-throughs).
  for (size_t u = 0; u < units_.size(); ++u) {
    auto& inst = units_[u];
    const auto& ports = inst.spec.ports();
    inst.port_index.assign(ports.size(), {});
    for (size_t p = 0; p < ports.size(); ++p) {
      const std::string where = "port " + port_label(static_cast<int>(u), static_cast<int>(p));
      const bool open = inst.peers[p].first < 0;
      if (open && ports[p].dir != PortDir::Probe && !ports[p].optional)
        throw ConfigError(where + " (" + to_string(ports[p].kind) + ", " + to_string(ports[p].dir) +
                          ") is not connected");
      const auto fields = stream_fields(ports[p].kind, ports[p].classes);
      for (size_t f = 0; f < fields.size(); ++f) {
        if (!open && ports[p].dir != PortDir::Probe) {
          const PortSpec& pp = units_[inst.peers[p].first].spec.ports()[inst.peers[p].second];
          const bool mine = ports[p].provided[f] >= 0 || ports[p].forwarded[f].first >= 0;
          const bool theirs = pp.provided[f] >= 0 || pp.forwarded[f].first >= 0;
          const std::string& peer = units_[inst.peers[p].first].name;
          if (mine && theirs)
            throw ConfigError(where + ": field '" + fields[f].name + "' is provided by both " + inst.name + " and " +
                              peer);
          if (!mine && !theirs)
            throw ConfigError(where + ": field '" + fields[f].name + "' is provided by neither " + inst.name + " nor " +
                              peer);
        }
        inst.port_index[p].push_back(resolve_field(static_cast<int>(u), static_cast<int>(p), static_cast<int>(f), 0));
      }
    }
  }
  for (auto& inst : units_) {  // runs of consecutive states, counted from the end of each port
    inst.port_runs.resize(inst.port_index.size());
    for (size_t p = 0; p < inst.port_index.size(); ++p) {
      const auto& idx = inst.port_index[p];
      auto& run = inst.port_runs[p];
      run.assign(idx.size(), 0);
      for (size_t f = idx.size(); f-- > 0;)
        if (idx[f] >= 0) run[f] = f + 1 < idx.size() && idx[f + 1] == idx[f] + 1 ? run[f + 1] + 1 : 1;
    }
  }
  resolve_drives(*this);  // refuses a controller's wiring that names nothing or cannot hold
  pool_ = std::make_shared<SystemPool>();
  finalized_ = true;
}

// ---------------------------------------------------------------- systems kept between runs
struct Flowsheet::SystemPool {
  std::mutex mutex;
  std::vector<std::unique_ptr<DaeSystem>> kept[2];  // [inline_explicit]
};

// Beyond this many of a kind, a returned system is freed: a sweep over a thread pool keeps one per worker, and a
// system of a large flowsheet holds megabytes (the extended Jacobian).
constexpr size_t kKeptSystems = 8;

std::shared_ptr<DaeSystem> Flowsheet::take_system(bool inline_explicit) const {
  if (!finalized_) throw std::logic_error("take_system before finalize");
  std::unique_ptr<DaeSystem> sys;
  {
    std::lock_guard<std::mutex> lock(pool_->mutex);
    auto& kept = pool_->kept[inline_explicit];
    if (!kept.empty()) sys = std::move(kept.back()), kept.pop_back();
  }
  if (sys)
    sys->begin_run();
  else
    sys = std::make_unique<DaeSystem>(*this, inline_explicit);
  std::weak_ptr<SystemPool> pool = pool_;
  return std::shared_ptr<DaeSystem>(sys.release(), [pool, inline_explicit](DaeSystem* done) {
    std::unique_ptr<DaeSystem> owned(done);
    if (!owned->completed()) return;
    if (auto p = pool.lock()) {
      std::lock_guard<std::mutex> lock(p->mutex);
      if (p->kept[inline_explicit].size() < kKeptSystems) p->kept[inline_explicit].push_back(std::move(owned));
    }
  });
}

// Global state index behind field f of port p of unit u, or -1 (an optional port left open reads zero).
int Flowsheet::resolve_field(int u, int p, int f, int depth) const {
  // every step of a resolution passes one port, so a chain longer than all ports is a loop
  int ports = 0;
  for (const auto& u : units_) ports += static_cast<int>(u.spec.ports().size());
  if (depth > ports + 1)
    throw ConfigError("port " + units_[u].name + "." + units_[u].spec.ports()[p].name +
                      ": a stream field cannot be resolved (forwarded fields form a loop, or no unit provides it)");
  const UnitInstance& inst = units_[u];
  const PortSpec& port = inst.spec.ports()[p];
  if (port.provided[f] >= 0) return inst.offset + port.provided[f];
  if (port.forwarded[f].first >= 0)
    return resolve_field(u, port.forwarded[f].first, port.forwarded[f].second, depth + 1);
  const auto [pu, pp] = inst.peers[p];
  if (pu < 0 || port.dir == PortDir::Probe) return -1;
  return resolve_field(pu, pp, f, depth + 1);
}

std::vector<std::string> Flowsheet::param_names() const {
  std::vector<std::string> v;
  for (const auto& u : units_)
    for (const auto& p : u.spec.params()) v.push_back(u.name + "." + p.name);
  return v;
}

int Flowsheet::param_id(const std::string& qualified) const {
  int id = 0;
  for (const auto& u : units_)
    for (const auto& p : u.spec.params()) {
      if (u.name + "." + p.name == qualified) return id;
      ++id;
    }
  const auto dot = qualified.find('.');
  // An old spelling of a renamed parameter stands for the new name (with a warning once per process).
  for (const auto& u : units_)
    if (dot != std::string::npos && u.name == qualified.substr(0, dot)) {
      const std::string renamed = renamed_param(u.unit->type(), qualified.substr(dot + 1));
      if (!renamed.empty() && u.spec.param_index(renamed) >= 0)  // this instance has it (its kernels declare it)
        return param_id(u.name + "." + use_renamed_param(u.unit->type(), u.name, qualified.substr(dot + 1)));
    }
  // Name the unit's parameters when the unit exists, else all units.
  std::string allowed;
  for (const auto& u : units_)
    if (dot != std::string::npos && u.name == qualified.substr(0, dot))
      for (const auto& p : u.spec.params()) allowed += (allowed.empty() ? "" : ", ") + p.name;
  if (!allowed.empty()) {
    // A parameter that moved to another unit (the particle system's densities, once the bed's) names its place.
    const std::string key = qualified.substr(dot + 1);
    std::string elsewhere;
    for (const auto& u : units_)
      for (const auto& p : u.spec.params())
        if (p.name == key && u.name != qualified.substr(0, dot)) elsewhere += (elsewhere.empty() ? "" : ", ") + u.name;
    throw ConfigError("unknown parameter '" + qualified + "' (parameters of " + qualified.substr(0, dot) + ": " +
                      allowed + ")" +
                      (elsewhere.empty() ? ""
                                         : "; '" + key + "' is a parameter of " + elsewhere + ": " +
                                               elsewhere.substr(0, elsewhere.find(',')) + "." + key));
  }
  std::string units;
  for (const auto& u : units_) units += (units.empty() ? "" : ", ") + u.name;
  throw ConfigError("unknown parameter '" + qualified + "': expected 'unit.param' with unit one of " + units);
}

std::pair<int, int> Flowsheet::param_location(int id) const {
  if (!param_table_.empty()) return param_table_.at(id);
  int k = id;
  for (size_t u = 0; u < units_.size(); ++u) {
    const int n = static_cast<int>(units_[u].params.size());
    if (k < n) return {int(u), k};
    k -= n;
  }
  throw std::out_of_range("parameter id");
}

const ParamSpec& Flowsheet::param_spec(int id) const {
  auto [u, k] = param_location(id);
  return units_[u].spec.params()[k];
}

std::string Flowsheet::qualified_name(int id) const {
  auto [u, k] = param_location(id);
  return units_[u].name + "." + units_[u].spec.params()[k].name;
}

int Flowsheet::link_source(int target) const {
  for (const auto& [t, s] : links_)
    if (t == target) return s;
  return -1;
}

double Flowsheet::linked_value(int source) const {
  auto [su, sk] = param_location(source);
  const auto& in = units_[su].inputs[sk];
  return in ? (*in)(0.0) : units_[su].params[sk];
}

// A link target reports the value it takes in a run (its source's), not the value stored before the last run.
// A parameter driven by a signal (signals.hpp) takes its source's value in every evaluation: a value given to it would
// never be used, so it is refused, naming the source.
static void refuse_driven(const Flowsheet& fs, int id, const std::string& what) {
  if (const std::string by = driven_by(fs, id); !by.empty())
    throw ConfigError(what + ": " + fs.qualified_name(id) + " is driven by " + by +
                      " in every evaluation; change the controller's parameters instead");
}

double Flowsheet::param_value(int id) const {
  const int src = link_source(id);
  if (src >= 0) return linked_value(src);
  auto [u, k] = param_location(id);
  return units_[u].params[k];
}

void Flowsheet::set_param_value(int id, double v) {
  const int src = link_source(id);
  // Setting a linked parameter to the value it follows changes nothing (a copy of every parameter value,
  // e.g. for a worker process, can be set back); any other value would be overwritten by the link at the
  // start of the run, so it is refused instead of being dropped silently.
  if (src >= 0 && !(v == linked_value(src))) {
    const ParamSpec& s = param_spec(id);
    const std::string target = qualified_name(id), source = qualified_name(src);
    throw ConfigError(target + " = " + fmt_num(v) + (s.unit.empty() || s.unit == "-" ? "" : " " + s.unit) +
                      ": cannot be set, it follows " + source + " by a link (links: " + target + ": " + source +
                      "); set " + source + " instead, or remove the link");
  }
  // The input would replace the value in every run: refused, never dropped silently.
  if (has_input(id)) {
    const ParamSpec& s = param_spec(id);
    const std::string q = qualified_name(id);
    throw ConfigError(q + " = " + fmt_num(v) + (s.unit.empty() || s.unit == "-" ? "" : " " + s.unit) +
                      ": cannot be set, it is driven by the time-dependent input " + q + " (inputs: " + q +
                      "); change the input's values, or remove the input to make " + q + " a constant");
  }
  auto [u, k] = param_location(id);
  if (!(v == units_[u].params[k])) refuse_driven(*this, id, qualified_name(id) + " = " + fmt_num(v));  // copies pass
  store_param(id, v);
}

std::pair<double, double> Flowsheet::bounds(int id) const {
  const ParamSpec& s = param_spec(id);
  double lo = s.lower, hi = s.upper;
  for (int t : linked_targets(id)) {
    lo = std::max(lo, param_spec(t).lower);
    hi = std::min(hi, param_spec(t).upper);
  }
  return {lo, hi};
}

// Names the link that narrows a source's bounds, if one does, for a message.
static std::string bound_rule(const Flowsheet& fs, int id) {
  const ParamSpec& s = fs.param_spec(id);
  const auto [lo, hi] = fs.bounds(id);
  std::ostringstream rule;
  rule.precision(10);
  rule << lo << " <= " << s.name << " <= " << hi;
  std::string why;
  for (int t : fs.linked_targets(id)) {
    const ParamSpec& ts = fs.param_spec(t);
    if (ts.lower > s.lower || ts.upper < s.upper)
      why += (why.empty() ? "" : ", ") + fs.qualified_name(t) + " in [" + fmt_num(ts.lower) + ", " + fmt_num(ts.upper) +
             "] follows it by a link";
  }
  if (!why.empty())
    rule << " (" << why << ")";
  else if (!s.source.empty())
    rule << " (" << s.source << ")";
  return rule.str();
}

void Flowsheet::store_param(int id, double v) {
  auto [u, k] = param_location(id);
  const ParamSpec& s = units_[u].spec.params()[k];
  const std::string where = units_[u].name + "." + s.name;
  if (!std::isfinite(v)) throw ConfigError(violation(where, v, s.unit, "a finite value"));
  const auto [lo, hi] = bounds(id);
  if (!(v >= lo && v <= hi)) throw ConfigError(violation(where, v, s.unit, bound_rule(*this, id)));
  units_[u].params[k] = v;
}

double Flowsheet::param(const std::string& qualified) const { return param_value(param_id(qualified)); }
void Flowsheet::set_param(const std::string& qualified, double v) { set_param_value(param_id(qualified), v); }

void Flowsheet::set_param_default(int id, double v, const std::string& source) {
  set_param_value(id, v);
  auto [u, k] = param_location(id);
  units_[u].spec.rebase_param(k, v, source);
}

void Flowsheet::set_input(const std::string& qualified, PiecewiseLinear input) {
  const int id = param_id(qualified);
  auto [u, k] = param_location(id);
  const ParamSpec& s = units_[u].spec.params()[k];
  refuse_driven(*this, id, "input " + qualified);
  if (const int src = link_source(id); src >= 0)
    throw ConfigError("input " + qualified + ": cannot be set, " + qualified + " follows " + qualified_name(src) +
                      " by a link (links: " + qualified + ": " + qualified_name(src) + "); give " +
                      qualified_name(src) + " the input instead, or remove the link");
  for (size_t i = 0; i < input.values().size(); ++i) {
    const double v = input.values()[i];
    if (!(v >= s.lower && v <= s.upper)) {
      std::ostringstream rule;
      rule.precision(10);
      rule << s.lower << " <= " << s.name << " <= " << s.upper;
      throw ConfigError(violation("input " + qualified + ".values[" + std::to_string(i) + "]", v, s.unit, rule.str()));
    }
  }
  // Parameters that follow this one by a link take only its value at t = 0.
  if (const auto [lo, hi] = bounds(id); !(input(0.0) >= lo && input(0.0) <= hi))
    throw ConfigError(violation("input " + qualified + " at t = 0 s", input(0.0), s.unit, bound_rule(*this, id)));
  units_[u].inputs[k] = std::move(input);
}

void Flowsheet::clear_input(const std::string& qualified) {
  auto [u, k] = param_location(param_id(qualified));
  units_[u].inputs[k].reset();
}

void Flowsheet::link(const std::string& target, const std::string& source) {
  const int t = param_id(target), s = param_id(source);
  if (t == s) throw ConfigError("link " + target + ": a parameter cannot follow itself");
  for (int id : {t, s}) refuse_driven(*this, id, "link " + target + " -> " + source);
  if (param_spec(t).unit != param_spec(s).unit)
    throw ConfigError("link " + target + " -> " + source + ": units differ (" + param_spec(t).unit + " vs " +
                      param_spec(s).unit + ")");
  for (const auto& [tt, ss] : links_)
    if (tt == t) throw ConfigError("link " + target + ": linked twice");
  if (link_source(s) >= 0)
    throw ConfigError("link " + target + " -> " + source + ": " + source + " itself follows " +
                      qualified_name(link_source(s)) + "; link " + target + " to " + qualified_name(link_source(s)));
  if (!linked_targets(t).empty())
    throw ConfigError("link " + target + " -> " + source + ": " + qualified_name(linked_targets(t)[0]) + " follows " +
                      target + "; a linked parameter cannot be followed in turn");
  if (has_input(t))
    throw ConfigError("link " + target + " -> " + source + ": " + target +
                      " has a time-dependent input, which the link would override; remove one of them");
  // The source may take only values its follower can start from.
  const ParamSpec &ts = param_spec(t), &ss = param_spec(s);
  const auto [lo, hi] = bounds(s);
  if (std::max(lo, ts.lower) > std::min(hi, ts.upper))
    throw ConfigError("link " + target + " -> " + source + ": no value is allowed for both (" + target + " in [" +
                      fmt_num(ts.lower) + ", " + fmt_num(ts.upper) + "] " + ts.unit + ", " + source + " in [" +
                      fmt_num(lo) + ", " + fmt_num(hi) + "] " + ss.unit + ")");
  links_.push_back({t, s});
  // The source's value (at t = 0) must be one its new follower can take.
  if (const double v = linked_value(s); !(v >= ts.lower && v <= ts.upper)) {
    const std::string rule = bound_rule(*this, s);  // names the new link
    links_.pop_back();
    throw ConfigError(violation(has_input(s) ? "input " + source + " at t = 0 s" : source, v, ss.unit, rule));
  }
}

std::vector<double> Flowsheet::run_params(int u) const {
  std::vector<double> p = units_.at(u).params;
  for (const auto& [t, s] : links_) {
    auto [tu, tk] = param_location(t);
    if (tu != u) continue;
    const double v = linked_value(s);
    const ParamSpec& spec = units_[tu].spec.params()[tk];
    if (!(v >= spec.lower && v <= spec.upper)) {
      std::ostringstream rule;
      rule.precision(10);
      rule << spec.lower << " <= " << spec.name << " <= " << spec.upper;
      throw ConfigError(violation(qualified_name(t), v, spec.unit, rule.str()) + " (" + qualified_name(t) +
                        " follows " + qualified_name(s) + " by a link)");
    }
    p[tk] = v;
  }
  return p;
}

void Flowsheet::check_units() const {
  for (size_t u = 0; u < units_.size(); ++u) {
    const int ui = static_cast<int>(u);
    const UnitInstance& inst = units_[u];
    const std::vector<double> p0 = run_params(ui);
    std::set<double> knots;
    for (const auto& in : inst.inputs)
      if (in) knots.insert(in->times().begin(), in->times().end());
    if (knots.empty()) {
      try {
        inst.unit->check(inst.spec, p0.data());
      } catch (const ConfigError& e) {
        throw ConfigError(qualify_unit_message(ui, e.what()));
      }
      continue;
    }
    // With inputs, the values a run sees: at every knot (the constant stored under an input is never used).
    std::vector<double> p = p0;
    for (double t : knots) {
      for (size_t k = 0; k < p.size(); ++k) p[k] = inst.inputs[k] ? (*inst.inputs[k])(t) : p0[k];
      try {
        inst.unit->check(inst.spec, p.data());
      } catch (const ConfigError& e) {
        std::string driven;
        for (size_t k = 0; k < p.size(); ++k)
          if (inst.inputs[k]) driven += (driven.empty() ? "" : ", ") + inst.name + "." + inst.spec.params()[k].name;
        throw ConfigError(qualify_unit_message(ui, e.what()) + " (at t = " + fmt_num(t) + " s of the inputs " + driven +
                          ")");
      }
    }
  }
}

// configure() throws messages relative to its unit ("t_off = 600 s: violates t_off >= t_on (1800 s)"):
// name the unit instance, as the parameter bounds do ("nozzle.t_off = ...").
std::string Flowsheet::qualify_unit_message(int u, const std::string& m) const {
  const UnitInstance& inst = units_.at(u);
  for (const auto& p : inst.spec.params())
    if (m.rfind(p.name + " = ", 0) == 0 || m.rfind(p.name + ": ", 0) == 0) return inst.name + "." + m;
  const std::string type_prefix = "unit " + inst.unit->type();
  if (m.rfind(type_prefix, 0) == 0)
    return "unit " + inst.name + " (" + inst.unit->type() + ")" + m.substr(type_prefix.size());
  return "unit " + inst.name + " (" + inst.unit->type() + "): " + m;
}

std::vector<int> Flowsheet::linked_targets(int source) const {
  std::vector<int> v;
  for (const auto& [t, s] : links_)
    if (s == source) v.push_back(t);
  return v;
}

bool Flowsheet::has_input(int id) const {
  auto [u, k] = param_location(id);
  return units_[u].inputs[k].has_value();
}

std::vector<double> Flowsheet::breakpoints(double t_end) const {
  std::set<double> bp;
  for (const auto& u : units_)
    for (double t : u.unit->breakpoints(u.params.data()))
      if (t > 0 && t < t_end) bp.insert(t);
  for (const auto& u : units_)
    for (const auto& in : u.inputs)
      if (in)
        for (double t : in->times())
          if (t > 0 && t < t_end) bp.insert(t);
  return {bp.begin(), bp.end()};
}

std::vector<std::string> Flowsheet::state_names() const {
  std::vector<std::string> v(n_states_);
  for (const auto& u : units_)
    for (size_t k = 0; k < u.spec.states().size(); ++k) v[u.offset + k] = u.state_prefix + u.spec.states()[k].name;
  return v;
}

const StateSpec& Flowsheet::state_spec(int global) const {
  const auto& u = units_.at(state_owner_.at(global));
  return u.spec.states()[global - u.offset];
}

int Flowsheet::state_unit(int global) const { return state_owner_.at(global); }

int Flowsheet::state_id(const std::string& qualified) const {
  const auto names = state_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == qualified) return static_cast<int>(i);
  throw ConfigError("unknown state '" + qualified + "'");
}

std::vector<std::string> Flowsheet::output_names() const {
  std::vector<std::string> v;
  for (const auto& u : units_)
    for (const auto& o : u.spec.outputs()) v.push_back(u.name + "." + o.name);
  return v;
}

int Flowsheet::n_outputs() const { return static_cast<int>(output_names().size()); }

}  // namespace granuflow
