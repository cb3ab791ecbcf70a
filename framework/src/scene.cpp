#include "granuflow/scene.hpp"

#include <sys/stat.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "events.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/materials.hpp"
#include "granuflow/plugin.hpp"
#include "granuflow/quantity.hpp"
#include "yaml_json.hpp"
#include "yaml_text.hpp"

namespace granuflow {
namespace {

std::string kind_name(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return "'" + shown(n.Scalar()) + "'";
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
    // A Monte Carlo scene (engine: monte_carlo, docs/monte_carlo.md) is valid, just not a flowsheet: say which
    // commands take it instead of listing the keys a flowsheet allows.
    if (const YAML::Node engine = root["engine"]; engine && engine.IsScalar() && engine.Scalar() == "monte_carlo")
      fail("engine",
           "monte_carlo: a scene for the Monte Carlo engine, not a flowsheet; `granuflow run` and "
           "`granuflow describe` take it (Python: granuflow.montecarlo.scene.Scene(path).run()), the other "
           "commands and granuflow.load() read flowsheets, which have no engine key");
    check_keys(root, "",
               {"scene", "description", "t_end", "output", "solver", "particles", "units", "connections", "inputs",
                "summary", "plots", "sweep", "notes", "links", "accuracy", "events", "checkpoints", "plugins"});
    Scene s;
    s.path = label_;
    s.name = scalar(required(root, "scene", ""), "scene");
    if (root["description"]) s.description = scalar(root["description"], "description");
    s.flowsheet = std::make_unique<Flowsheet>(s.name);
    Flowsheet& fs = *s.flowsheet;

    Params params;
    std::map<std::string, std::string> given;  // unit.param -> scene key that set it (params or inputs)
    if (root["plugins"]) load_plugins(root["plugins"]);
    load_units(root, fs, params);
    if (root["connections"]) load_connections(root["connections"], fs);
    try {
      fs.finalize();
    } catch (const ConfigError& e) {
      fail("connections", e.what());
    }
    const std::vector<std::string> unsupplied = material_.empty() ? std::vector<std::string>{} : apply_material_(fs);
    for (const auto& [unit, node] : params)
      load_params((unit == "particles" && root["particles"] ? "" : "units.") + unit + ".params", unit, node, fs, given);
    if (root["inputs"]) load_inputs(root["inputs"], fs, given);
    if (root["links"]) load_links(root["links"], fs, given);
    check_across_parameters(fs, given);
    // What the material does not give keeps the unit's built-in value (paper 001's maltodextrin), said where the
    // value is shown (describe's source, the run's summary and a note), unless the scene sets it.
    for (const std::string& q : unsupplied)
      if (!given.count(q)) {
        const int id = fs.param_id(q);
        fs.set_param_default(
            id, fs.param_value(id),
            "not given by material " + material_ + "; built-in value from " + fs.param_spec(id).source);
        s.material_unsupplied.push_back(q);
      }
    s.material = material_;
    s.options.t_end = quantity(required(root, "t_end", ""), "t_end", "s");
    if (root["output"]) load_output(root["output"], s.options);
    if (root["solver"]) load_solver(root["solver"], s.options);
    if (root["events"]) s.options.events = detail::load_events(root["events"], fs, label_, units_);
    if (root["checkpoints"]) s.options.checkpoints = detail::load_checkpoints(root["checkpoints"], label_);
    try {
      s.options.validate(true);
    } catch (const ConfigError& e) {
      rethrow(e);
    }
    if (root["summary"]) load_summary(root["summary"], fs, s.summary);
    YAML::Node extra;
    for (const char* k : {"plots", "sweep", "notes", "accuracy"})  // accuracy: read by granuflow.accuracy
      if (root[k]) extra[k] = root[k];
    for (const char* k : {"plots", "sweep", "notes", "accuracy", "particles", "inputs", "events"})
      if (root[k]) try {
          s.sections_json[k] = yaml_json(root[k]);
        } catch (const ConfigError& e) {
          rethrow(ConfigError(std::string("section '") + k + "', " + e.what()));
        }
    YAML::Emitter em;
    em << extra;
    s.extra_yaml = em.c_str();
    return s;
  }

 private:
  using Params = std::vector<std::pair<std::string, YAML::Node>>;  // unit name, its params node

  // Plugins before the units that may name their types (granuflow/plugin.hpp); a relative path is taken from the
  // scene file's folder.
  void load_plugins(const YAML::Node& p) const {
    if (!p.IsSequence()) fail("plugins", "expected a list of shared-library paths, got " + kind_name(p));
    const size_t slash = label_.rfind('/');
    const std::string dir = slash == std::string::npos ? "" : label_.substr(0, slash + 1);
    for (size_t i = 0; i < p.size(); ++i) {
      const std::string at = "plugins[" + std::to_string(i) + "]";
      std::string file = scalar(p[i], at);
      if (!file.empty() && file[0] != '/') file = dir + file;
      try {
        load_plugin(file);
      } catch (const ConfigError& e) {
        fail(at, e.what());
      }
    }
  }

  // One unit per entry; the `particles` section is the unit "particles" of type particles (the size grid and
  // product shared by every particle unit), declared first so that the others find it.
  void load_units(const YAML::Node& root, Flowsheet& fs, Params& params) const {
    const YAML::Node units = required(root, "units", "");
    if (!units.IsMap() || units.size() == 0) fail("units", "expected a non-empty mapping of unit name -> {type, ...}");
    check_unique(units, "units");
    if (root["particles"]) {
      if (units["particles"]) fail("units.particles", "'particles' is the name of the scene's particle system");
      add_unit(fs, "particles", "particles", root["particles"], "particles", params);
    }
    for (const auto& kv : units) {
      const std::string name = key_of(kv.first, "units");
      add_unit(fs, name, "units." + name, kv.second, "", params);
    }
  }

  // `implied`: the type of a section that is a unit by its place (particles), or "" when the entry names its type.
  void add_unit(Flowsheet& fs, const std::string& name, const std::string& at, const YAML::Node& u,
                const std::string& implied, Params& params) const {
    if (!u.IsMap())
      fail(at, std::string("expected a mapping with ") + (implied.empty() ? "'type'" : "'settings' and 'params'") +
                   ", got " + kind_name(u));
    if (implied.empty())
      check_keys(u, at, {"type", "settings", "params"});
    else
      check_keys(u, at, {"settings", "params", "material"});
    if (u["material"]) {
      material_ = scalar(u["material"], at + ".material");
      try {
        find_material(material_);
      } catch (const ConfigError& e) {
        fail(at + ".material", e.what());
      }
    }
    const std::string type = implied.empty() ? scalar(required(u, "type", at), at + ".type") : implied;
    std::map<std::string, std::string> settings;
    if (u["settings"]) {
      if (!u["settings"].IsMap()) fail(at + ".settings", "expected a mapping, got " + kind_name(u["settings"]));
      check_unique(u["settings"], at + ".settings");
      for (const auto& st : u["settings"])
        settings[key_of(st.first, at + ".settings")] =
            scalar(st.second, at + ".settings." + key_of(st.first, at + ".settings"));
    }
    try {
      fs.add_unit(name, units_.create(type, label_ + ": " + at + ".type"),
                  Settings(label_ + ": " + at + ".settings", settings));
    } catch (const ConfigError& e) {
      rethrow(e);
    }
    if (u["params"]) params.emplace_back(name, u["params"]);
  }

  // The named material's values become the defaults of the parameters it describes (materials.hpp); returns those
  // it does not give, which the scene must.
  std::vector<std::string> apply_material_(Flowsheet& fs) const {
    try {
      return apply_material(fs, find_material(material_), "");
    } catch (const ConfigError& e) {
      fail("particles.material", e.what());
    }
    return {};
  }

  void load_connections(const YAML::Node& c, Flowsheet& fs) const {
    if (!c.IsSequence()) fail("connections", "expected a list of \"unit.port -> unit.port\"");
    for (size_t i = 0; i < c.size(); ++i) {
      const std::string at = "connections[" + std::to_string(i) + "]";
      const std::string text = scalar(c[i], at);
      const auto arrow = text.find("->");
      if (arrow == std::string::npos) fail(at, "'" + shown(text) + "': expected \"unit.port -> unit.port\"");
      try {
        fs.connect(trim(text.substr(0, arrow)), trim(text.substr(arrow + 2)));
      } catch (const ConfigError& e) {
        fail(at, e.what());
      }
    }
  }

  void load_params(const std::string& at, const std::string& unit, const YAML::Node& node, Flowsheet& fs,
                   std::map<std::string, std::string>& given) const {
    if (!node.IsMap()) fail(at, "expected a mapping of parameter -> value, got " + kind_name(node));
    check_unique(node, at);
    for (const auto& p : node) {
      const std::string key = key_of(p.first, at);
      std::string q = unit + "." + key;
      try {
        q = fs.qualified_name(fs.param_id(q));  // the current name of a renamed parameter's old spelling
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

  void load_links(const YAML::Node& l, Flowsheet& fs, const std::map<std::string, std::string>& given) const {
    if (!l.IsMap()) fail("links", "expected a mapping of unit.param -> unit.param it follows");
    check_unique(l, "links");
    for (const auto& kv : l) {
      const std::string target = key_of(kv.first, "links");
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

  // Checks across parameters of a unit (t_off >= t_on ...), as a run would find them, named by the scene key that
  // gave the parameter (or its default).
  void check_across_parameters(Flowsheet& fs, const std::map<std::string, std::string>& given) const {
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
  }

  void load_summary(const YAML::Node& sm, const Flowsheet& fs, std::map<std::string, std::string>& summary) const {
    if (!sm.IsMap()) fail("summary", "expected a mapping of summary key -> unit.state or unit.output");
    check_unique(sm, "summary");
    const auto states = fs.state_names();
    const auto outputs = fs.output_names();
    for (const auto& kv : sm) {
      const std::string key = key_of(kv.first, "summary"), src = scalar(kv.second, "summary." + key);
      if (std::find(states.begin(), states.end(), src) == states.end() &&
          std::find(outputs.begin(), outputs.end(), src) == outputs.end())
        fail("summary." + key, "'" + shown(src) + "' is neither a state nor a reported output of the flowsheet");
      summary[key] = src;
    }
  }

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
      const std::string k = key_of(kv.first, at);
      if (!allowed.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(at.empty() ? k : at + "." + k, "unknown key (allowed: " + list + ")");
      }
    }
  }
  // A key is a plain name: yaml-cpp would convert a list or mapping key with "bad conversion", naming nothing.
  std::string key_of(const YAML::Node& k, const std::string& at) const {
    if (!k.IsScalar() || k.Scalar().empty())
      fail(at, "a key must be a plain name, got " + (k.IsScalar() ? std::string("an empty key") : kind_name(k)));
    return k.Scalar();
  }
  // YAML parsers keep the last of two equal keys; a scene must say each thing once.
  void check_unique(const YAML::Node& m, const std::string& at) const {
    std::set<std::string> seen;
    for (const auto& kv : m) {
      const std::string k = key_of(kv.first, at);
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
      fail(at, "'" + shown(text) + "' is not a number with an optional unit (e.g. \"60 degC\")");
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
    if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) fail(at, "'" + shown(text) + "' is not a number");
    return v;
  }
  // A count. Its range is SimOptions::validate()'s to check, but a fraction or a number beyond int cannot be
  // held by the option at all (the cast would truncate it, or be undefined).
  int whole_number(const YAML::Node& n, const std::string& at) const {
    constexpr int kMax = std::numeric_limits<int>::max();
    const double v = number(n, at);
    if (v != std::floor(v) || std::abs(v) > kMax)
      fail(at, "'" + shown(n.Scalar()) + "' is not a whole number between -" + std::to_string(kMax) + " and " +
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
    try {  // "solver.method = 'x': not one of ...", after the file's name
      if (s["linear_solver"])
        opt.linear_solver = parse_linear_solver(scalar(s["linear_solver"], "solver.linear_solver"));
      if (s["method"]) opt.method = parse_method(scalar(s["method"], "solver.method"));
    } catch (const ConfigError& e) {
      rethrow(e);
    }
    if (s["dense_limit"]) opt.dense_limit = whole_number(s["dense_limit"], "solver.dense_limit");
  }
  void load_inputs(const YAML::Node& in, Flowsheet& fs, std::map<std::string, std::string>& given) const {
    if (!in.IsMap()) fail("inputs", "expected a mapping of unit.param -> {times, values, interp}");
    check_unique(in, "inputs");
    for (const auto& kv : in) {
      std::string q = key_of(kv.first, "inputs");
      const std::string at = "inputs." + q;
      try {
        q = fs.qualified_name(fs.param_id(q));
      } catch (const ConfigError& e) {
        fail(at, e.what());
      }
      // The input would replace the constant in every run, so the constant would be ignored.
      if (auto g = given.find(q); g != given.end())
        fail(at, q + " is given both as " + g->second + " and as " + at +
                     "; an input replaces the constant value in every run: remove one of them");
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
          fail(at + ".interp", "'" + shown(s) + "': not one of linear, step");
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
  mutable std::string material_;  // particles.material, "" when the scene names none
};

}  // namespace

double parse_param_value(const Flowsheet& fs, const std::string& qualified, const std::string& text,
                         const std::string& where) {
  const ParamSpec& spec = fs.param_spec(fs.param_id(qualified));
  double v;
  std::string unit;
  if (!parse_quantity(text, &v, &unit) || !std::isfinite(v))
    throw ConfigError(where + " = '" + shown(text) +
                      "': expected a number with an optional unit (SI unit: " + spec.unit + ")");
  return to_si(v, unit, spec.unit, where);
}

Scene load_scene_text(const std::string& text, const std::string& label, const Registry<Unit>& units) {
  try {
    check_yaml_text(text, label, "scene");
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
    } catch (const YAML::Exception& e) {  // valid YAML, but no scene; the loader names keys before converting
      throw ConfigError(label + ": " + e.what());
    }
  } catch (const ConfigError& e) {
    throw ConfigError(one_line(e.what()));
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

// Only a regular file is read: a directory "opens" as an empty stream on some systems, and a fifo or a device
// would block or never end.
static std::string read_scene_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw ConfigError(path + ": cannot read the scene file (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw ConfigError(path + ": is a directory; expected a scene file (.yaml)");
  if (!S_ISREG(st.st_mode)) throw ConfigError(path + ": not a regular file; expected a scene file (.yaml)");
  if (static_cast<uint64_t>(st.st_size) > kMaxSceneBytes)
    throw ConfigError(path + ": " + std::to_string(st.st_size) + " bytes; a scene file is at most " +
                      std::to_string(kMaxSceneBytes) + " bytes");
  errno = 0;
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ConfigError(path + ": cannot read the scene file (" + std::strerror(errno ? errno : EACCES) + ")");
  // Sized by the file, not by the limit: a zeroed megabyte is 256 fresh pages, about 3 ms of a 0.1-s run on a machine
  // whose page faults are slow. A file that grew since stat() is read on up to one byte past the limit, which the
  // text's guard refuses (yaml_text.cpp).
  const size_t cap = kMaxSceneBytes + 1;
  std::string text(std::min(static_cast<size_t>(st.st_size) + 1, cap), '\0');
  size_t got = 0;
  while (true) {
    f.read(&text[got], static_cast<std::streamsize>(text.size() - got));
    if (f.bad()) throw ConfigError(path + ": cannot read the scene file (read error)");
    got += static_cast<size_t>(f.gcount());
    if (got < text.size() || text.size() == cap) break;  // the end of the file, or past the limit
    text.resize(std::min(cap, 2 * text.size()));
  }
  text.resize(got);
  return text;
}

Scene load_scene(const std::string& path, const Registry<Unit>& units) {
  return load_scene_text(read_scene_file(path), path, units);
}

}  // namespace granuflow
