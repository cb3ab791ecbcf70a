// libFuzzer target: the calibration core's experiment check (check_experiments, calibration.hpp) against the
// headline scene. The Python layer reads experiment files and hands the core a list of experiments; this
// target builds that list from YAML of the same shape, with numbers read by strtod so that nan, inf, 1e999
// and -0 reach the core as they could from Python:
//   - {name: C1, t_end: 3600, settings: {inlet.T: 313.15},
//      observations: [{name: gas.T, t: [0, 600], value: [330, nan], sigma_abs: 2}]}
// Contract: the check accepts or throws ConfigError with one line naming the experiment; anything else is a
// finding. Inputs that are not YAML of this shape are skipped (the Python layer refuses those itself).
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "granuflow/calibration.hpp"
#include "granuflow/errors.hpp"
#include "units/registry.hpp"

namespace {

using namespace granuflow;

double number(const YAML::Node& n) {
  if (!n.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a number");
  return std::strtod(n.Scalar().c_str(), nullptr);
}

std::vector<double> numbers(const YAML::Node& n) {
  std::vector<double> v;
  if (!n) return v;
  if (!n.IsSequence()) throw YAML::Exception(YAML::Mark::null_mark(), "not a list");
  for (const auto& x : n) v.push_back(number(x));
  return v;
}

std::vector<Experiment> experiments(const YAML::Node& root) {
  std::vector<Experiment> out;
  if (!root.IsSequence()) throw YAML::Exception(YAML::Mark::null_mark(), "not a list");
  for (const auto& e : root) {
    Experiment x;
    if (!e.IsMap()) throw YAML::Exception(YAML::Mark::null_mark(), "not a mapping");
    if (e["name"]) x.name = e["name"].as<std::string>();
    if (e["t_end"]) x.t_end = number(e["t_end"]);
    if (const auto s = e["settings"]; s && s.IsMap())
      for (const auto& kv : s) x.settings.emplace_back(kv.first.as<std::string>(), number(kv.second));
    if (const auto os = e["observations"]; os && os.IsSequence())
      for (const auto& o : os) {
        if (!o.IsMap()) continue;
        Observation ob;
        if (o["name"]) ob.name = o["name"].as<std::string>();
        ob.t = numbers(o["t"]);
        ob.value = numbers(o["value"]);
        if (o["sigma_abs"]) ob.sigma_abs = number(o["sigma_abs"]);
        if (o["sigma_rel"]) ob.sigma_rel = number(o["sigma_rel"]);
        x.observations.push_back(std::move(ob));
      }
    out.push_back(std::move(x));
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Scene scene = load_scene(GRANUFLOW_HEADLINE_SCENE, units::builtin());
  std::vector<Experiment> exps;
  try {
    exps = experiments(YAML::Load(std::string(reinterpret_cast<const char*>(data), size)));
  } catch (const YAML::Exception&) {
    return 0;
  }
  try {
    check_experiments(*scene.flowsheet, exps);
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    if (m.rfind("experiment '", 0) != 0 || m.size() > 1500) {
      std::fprintf(stderr, "message breaks the contract (%zu chars): %s\n", m.size(), m.c_str());
      std::abort();
    }
  }
  return 0;
}
