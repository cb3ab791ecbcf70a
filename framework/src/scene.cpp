#include "granuflow/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"

namespace granuflow {
namespace {

std::string kind_name(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return "'" + n.Scalar() + "'";
    case YAML::NodeType::Null:
      return "empty";
    default:
      return "undefined";
  }
}

class Loader {
 public:
  Loader(std::string label, const Registry<Unit>& units) : label_(std::move(label)), units_(units) {}

  Scene load(const YAML::Node& root) {
    if (!root.IsMap()) fail("", "the file must be a mapping of scene keys, got " + kind_name(root));
    check_keys(root, "",
               {"scene", "description", "t_end", "output", "solver", "particles", "units", "connections", "inputs",
                "summary", "plots", "sweep", "notes", "links"});
    Scene s;
    s.path = label_;
    s.name = scalar(required(root, "scene", ""), "scene");
    if (root["description"]) s.description = scalar(root["description"], "description");
    s.flowsheet = std::make_unique<Flowsheet>(s.name);
    Flowsheet& fs = *s.flowsheet;

    const YAML::Node units = required(root, "units", "");
    if (!units.IsMap() || units.size() == 0) fail("units", "expected a non-empty mapping of unit name -> {type, ...}");
    check_unique(units, "units");
    std::vector<std::pair<std::string, YAML::Node>> params;
    std::map<std::string, std::string> given;  // unit.param -> scene key that set it (params or inputs)
    // One unit per entry; the `particles` section is the unit "particles" of type particles (the size grid and
    // product shared by every particle unit), declared first so that the others find it.
    auto add = [&](const std::string& name, const std::string& at, const YAML::Node& u, const std::string& implied) {
      if (!u.IsMap())
        fail(at, std::string("expected a mapping with ") + (implied.empty() ? "'type'" : "'settings' and 'params'") +
                     ", got " + kind_name(u));
      if (implied.empty())
        check_keys(u, at, {"type", "settings", "params"});
      else
        check_keys(u, at, {"settings", "params"});
      const std::string type = implied.empty() ? scalar(required(u, "type", at), at + ".type") : implied;
      std::map<std::string, std::string> settings;
      if (u["settings"]) {
        if (!u["settings"].IsMap()) fail(at + ".settings", "expected a mapping, got " + kind_name(u["settings"]));
        check_unique(u["settings"], at + ".settings");
        for (const auto& st : u["settings"])
          settings[st.first.as<std::string>()] = scalar(st.second, at + ".settings." + st.first.as<std::string>());
      }
      try {
        fs.add_unit(name, units_.create(type, label_ + ": " + at + ".type"),
                    Settings(label_ + ": " + at + ".settings", settings));
      } catch (const ConfigError& e) {
        rethrow(e);
      }
      if (u["params"]) params.emplace_back(name, u["params"]);
    };
    if (root["particles"]) {
      if (units["particles"]) fail("units.particles", "'particles' is the name of the scene's particle system");
      add("particles", "particles", root["particles"], "particles");
    }
    for (const auto& kv : units) {
      const std::string name = kv.first.as<std::string>();
      add(name, "units." + name, kv.second, "");
    }

    if (root["connections"]) {
      const YAML::Node c = root["connections"];
      if (!c.IsSequence()) fail("connections", "expected a list of \"unit.port -> unit.port\"");
      for (size_t i = 0; i < c.size(); ++i) {
        const std::string at = "connections[" + std::to_string(i) + "]";
        const std::string text = scalar(c[i], at);
        const auto arrow = text.find("->");
        if (arrow == std::string::npos) fail(at, "'" + text + "': expected \"unit.port -> unit.port\"");
        try {
          fs.connect(trim(text.substr(0, arrow)), trim(text.substr(arrow + 2)));
        } catch (const ConfigError& e) {
          fail(at, e.what());
        }
      }
    }
    try {
      fs.finalize();
    } catch (const ConfigError& e) {
      fail("connections", e.what());
    }

    for (const auto& [unit, node] : params) {
      const std::string at = (unit == "particles" && root["particles"] ? "" : "units.") + unit + ".params";
      if (!node.IsMap()) fail(at, "expected a mapping of parameter -> value, got " + kind_name(node));
      check_unique(node, at);
      for (const auto& p : node) {
        const std::string key = p.first.as<std::string>();
        const std::string q = unit + "." + key;
        try {
          fs.param_id(q);
        } catch (const ConfigError& e) {
          fail(at + "." + key, e.what());
        }
        const double v = parse_param_value(fs, q, scalar(p.second, at + "." + key), label_ + ": " + at + "." + key);
        try {
          fs.set_param(q, v);
        } catch (const ConfigError& e) {
          fail(at + "." + key, e.what());
        }
        given[q] = at + "." + key;
      }
    }

    if (root["inputs"]) load_inputs(root["inputs"], fs, given);
    if (root["links"]) {
      const YAML::Node l = root["links"];
      if (!l.IsMap()) fail("links", "expected a mapping of unit.param -> unit.param it follows");
      check_unique(l, "links");
      for (const auto& kv : l) {
        const std::string target = kv.first.as<std::string>();
        const std::string source = scalar(kv.second, "links." + target);
        // A value given for a parameter that follows another would be overwritten at the start of every run.
        if (auto g = given.find(target); g != given.end())
          fail("links." + target, target + " follows " + source + " by this link but is also given as " + g->second +
                                      "; remove one of them (set " + source + " instead)");
        try {
          fs.link(target, source);
        } catch (const ConfigError& e) {
          fail("links." + target, e.what());
        }
      }
    }
    // Checks across parameters of a unit (t_off >= t_on ...), as a run would find them.
    try {
      fs.check_units();
    } catch (const ConfigError& e) {
      std::string m = e.what();
      for (const auto& q : fs.param_names())
        if (m.rfind(q + " = ", 0) == 0 || m.rfind(q + ": ", 0) == 0) {
          auto g = given.find(q);
          const auto dot = q.find('.');
          m = (g != given.end() ? g->second
                                : "units." + q.substr(0, dot) + ".params." + q.substr(dot + 1) + " (default)") +
              m.substr(q.size());
          break;
        }
      fail("", m);
    }
    s.options.t_end = quantity(required(root, "t_end", ""), "t_end", "s");
    if (root["output"]) load_output(root["output"], s.options);
    if (root["solver"]) load_solver(root["solver"], s.options);
    try {
      s.options.validate(true);
    } catch (const ConfigError& e) {
      rethrow(e);
    }
    if (root["summary"]) {
      const YAML::Node sm = root["summary"];
      if (!sm.IsMap()) fail("summary", "expected a mapping of summary key -> unit.state or unit.output");
      check_unique(sm, "summary");
      const auto states = fs.state_names();
      const auto outputs = fs.output_names();
      for (const auto& kv : sm) {
        const std::string key = kv.first.as<std::string>(), src = scalar(kv.second, "summary." + key);
        if (std::find(states.begin(), states.end(), src) == states.end() &&
            std::find(outputs.begin(), outputs.end(), src) == outputs.end())
          fail("summary." + key, "'" + src + "' is neither a state nor a reported output of the flowsheet");
        s.summary[key] = src;
      }
    }
    YAML::Node extra;
    for (const char* k : {"plots", "sweep", "notes"})
      if (root[k]) extra[k] = root[k];
    YAML::Emitter em;
    em << extra;
    s.extra_yaml = em.c_str();
    return s;
  }

 private:
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ConfigError(label_ + ": " + (key.empty() ? "" : key + ": ") + what);
  }
  [[noreturn]] void rethrow(const ConfigError& e) const {
    const std::string m = e.what();
    if (m.rfind(label_, 0) == 0) throw e;
    throw ConfigError(label_ + ": " + m);
  }
  static std::string trim(const std::string& s) {
    const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
  }
  void check_keys(const YAML::Node& m, const std::string& at, const std::set<std::string>& allowed) const {
    check_unique(m, at);
    for (const auto& kv : m) {
      const std::string k = kv.first.as<std::string>();
      if (!allowed.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(at.empty() ? k : at + "." + k, "unknown key (allowed: " + list + ")");
      }
    }
  }
  // YAML parsers keep the last of two equal keys; a scene must say each thing once.
  void check_unique(const YAML::Node& m, const std::string& at) const {
    std::set<std::string> seen;
    for (const auto& kv : m) {
      const std::string k = kv.first.as<std::string>();
      if (!seen.insert(k).second) fail(at.empty() ? k : at + "." + k, "given twice");
    }
  }
  YAML::Node required(const YAML::Node& m, const std::string& key, const std::string& at) const {
    if (!m[key]) fail(at.empty() ? key : at + "." + key, "missing required key");
    return m[key];
  }
  std::string scalar(const YAML::Node& n, const std::string& at) const {
    if (!n.IsScalar()) fail(at, "expected a single value, got " + kind_name(n));
    return n.Scalar();
  }
  double quantity(const YAML::Node& n, const std::string& at, const std::string& si) const {
    double v;
    std::string unit;
    const std::string text = scalar(n, at);
    if (!parse_quantity(text, &v, &unit) || !std::isfinite(v))
      fail(at, "'" + text + "' is not a number with an optional unit (e.g. \"60 degC\")");
    return to_si(v, unit, si, label_ + ": " + at);
  }
  void load_output(const YAML::Node& o, SimOptions& opt) const {
    if (!o.IsMap()) fail("output", "expected a mapping with 'n' or 'times'");
    check_keys(o, "output", {"n", "times"});
    if (o["n"]) opt.n_out = whole_number(o["n"], "output.n");
    if (o["times"]) {
      if (!o["times"].IsSequence() || o["times"].size() == 0)
        fail("output.times", (o["times"].IsSequence() ? std::string("[]") : kind_name(o["times"])) +
                                 ": expected a non-empty list of times in [0, t_end] (or output: {n: count})");
      if (o["n"]) fail("output", "give either n or times, not both");
      for (size_t i = 0; i < o["times"].size(); ++i)
        opt.t_out.push_back(quantity(o["times"][i], "output.times[" + std::to_string(i) + "]", "s"));
    }
  }
  double number(const YAML::Node& n, const std::string& at) const {
    const std::string text = scalar(n, at);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) fail(at, "'" + text + "' is not a number");
    return v;
  }
  // A count. Its range is SimOptions::validate()'s to check, but a fraction or a number beyond int cannot be
  // held by the option at all (the cast would truncate it, or be undefined).
  int whole_number(const YAML::Node& n, const std::string& at) const {
    constexpr int kMax = std::numeric_limits<int>::max();
    const double v = number(n, at);
    if (v != std::floor(v) || std::abs(v) > kMax)
      fail(at, "'" + n.Scalar() + "' is not a whole number between -" + std::to_string(kMax) + " and " +
                   std::to_string(kMax));
    return static_cast<int>(v);
  }
  void load_solver(const YAML::Node& s, SimOptions& opt) const {
    if (!s.IsMap()) fail("solver", "expected a mapping");
    check_keys(s, "solver", {"rtol", "atol", "max_steps", "max_step", "linear_solver", "dense_limit", "method"});
    if (s["rtol"]) opt.rtol = number(s["rtol"], "solver.rtol");
    if (s["atol"]) opt.atol = number(s["atol"], "solver.atol");
    if (s["max_steps"]) opt.max_steps = whole_number(s["max_steps"], "solver.max_steps");
    if (s["max_step"]) opt.max_step = quantity(s["max_step"], "solver.max_step", "s");
    if (s["linear_solver"]) opt.linear_solver = scalar(s["linear_solver"], "solver.linear_solver");
    if (s["method"]) opt.method = scalar(s["method"], "solver.method");
    if (s["dense_limit"]) opt.dense_limit = whole_number(s["dense_limit"], "solver.dense_limit");
  }
  void load_inputs(const YAML::Node& in, Flowsheet& fs, std::map<std::string, std::string>& given) const {
    if (!in.IsMap()) fail("inputs", "expected a mapping of unit.param -> {times, values, interp}");
    check_unique(in, "inputs");
    for (const auto& kv : in) {
      const std::string q = kv.first.as<std::string>(), at = "inputs." + q;
      try {
        fs.param_id(q);
      } catch (const ConfigError& e) {
        fail(at, e.what());
      }
      const YAML::Node n = kv.second;
      if (!n.IsMap()) fail(at, "expected a mapping with times and values");
      check_keys(n, at, {"times", "values", "interp"});
      const YAML::Node ts = required(n, "times", at), vs = required(n, "values", at);
      if (!ts.IsSequence() || !vs.IsSequence()) fail(at, "times and values must be lists");
      std::vector<double> t, v;
      for (size_t i = 0; i < ts.size(); ++i)
        t.push_back(quantity(ts[i], at + ".times[" + std::to_string(i) + "]", "s"));
      for (size_t i = 0; i < vs.size(); ++i)
        v.push_back(parse_param_value(fs, q, scalar(vs[i], at + ".values[" + std::to_string(i) + "]"),
                                      label_ + ": " + at + ".values[" + std::to_string(i) + "]"));
      auto interp = PiecewiseLinear::Interp::kLinear;
      if (n["interp"]) {
        const std::string s = scalar(n["interp"], at + ".interp");
        if (s == "step")
          interp = PiecewiseLinear::Interp::kStep;
        else if (s != "linear")
          fail(at + ".interp", "'" + s + "': not one of linear, step");
      }
      try {
        fs.set_input(q, PiecewiseLinear(t, v, interp, label_ + ": " + at));
      } catch (const ConfigError& e) {
        rethrow(e);
      }
      given[q] = at;
    }
  }

  std::string label_;
  const Registry<Unit>& units_;
};

}  // namespace

double parse_param_value(const Flowsheet& fs, const std::string& qualified, const std::string& text,
                         const std::string& where) {
  const ParamSpec& spec = fs.param_spec(fs.param_id(qualified));
  double v;
  std::string unit;
  if (!parse_quantity(text, &v, &unit) || !std::isfinite(v))
    throw ConfigError(where + " = '" + text + "': expected a number with an optional unit (SI unit: " + spec.unit +
                      ")");
  return to_si(v, unit, spec.unit, where);
}

Scene load_scene_text(const std::string& text, const std::string& label, const Registry<Unit>& units) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(label + ": not valid YAML: " + e.what());
  }
  try {
    Scene s = Loader(label, units).load(root);
    s.text = text;
    return s;
  } catch (const YAML::Exception& e) {  // e.g. a key that is a list: valid YAML, but no scene
    throw ConfigError(label + ": " + e.what());
  }
}

Scene clone_scene(const Scene& src, const Registry<Unit>& units) {
  Scene s = load_scene_text(src.text, src.path, units);
  s.options = src.options;
  auto& to = s.flowsheet->units();
  const auto& from = src.flowsheet->units();
  for (size_t u = 0; u < from.size(); ++u) {
    to[u].params = from[u].params;
    to[u].inputs = from[u].inputs;
  }
  return s;
}

Scene load_scene(const std::string& path, const Registry<Unit>& units) {
  std::ifstream f(path);
  if (!f) throw ConfigError(path + ": cannot open the scene file");
  std::stringstream ss;
  ss << f.rdbuf();
  return load_scene_text(ss.str(), path, units);
}

}  // namespace granuflow
