#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"
#include "granuflow/unit.hpp"

namespace granuflow {

int UnitSpec::add_state(std::string name, StateKind kind, std::string unit, double scale) {
  if (state_index(name) >= 0) throw std::logic_error("state '" + name + "' declared twice");
  if (!is_known_si_unit(unit)) throw std::logic_error("state '" + name + "' has unknown SI unit '" + unit + "'");
  if (!(scale > 0) || !std::isfinite(scale)) throw std::logic_error("state '" + name + "' needs a positive scale");
  states_.push_back({std::move(name), kind, std::move(unit), scale});
  return static_cast<int>(states_.size()) - 1;
}

int UnitSpec::add_param(ParamSpec spec) {
  if (param_index(spec.name) >= 0) throw std::logic_error("parameter '" + spec.name + "' declared twice");
  if (!is_known_si_unit(spec.unit))
    throw std::logic_error("parameter '" + spec.name + "' has unknown SI unit '" + spec.unit + "'");
  if (!(spec.lower <= spec.value && spec.value <= spec.upper))
    throw std::logic_error("parameter '" + spec.name + "' default outside its bounds");
  params_.push_back(std::move(spec));
  return static_cast<int>(params_.size()) - 1;
}

int UnitSpec::add_port(std::string name, StreamKind kind, PortDir dir, int classes, bool optional) {
  for (const auto& p : ports_)
    if (p.name == name) throw std::logic_error("port '" + name + "' declared twice");
  PortSpec p{std::move(name), kind, dir, classes, optional, {}, {}};
  p.provided.assign(stream_fields(kind, classes).size(), -1);
  ports_.push_back(std::move(p));
  return static_cast<int>(ports_.size()) - 1;
}

void UnitSpec::set_port_grid(int port, std::vector<double> diameters) {
  if (static_cast<int>(diameters.size()) != ports_.at(port).classes)
    throw std::logic_error("port '" + ports_.at(port).name + "': grid size differs from its class count");
  ports_.at(port).grid = std::move(diameters);
}

void UnitSpec::provide(int port, int field, int state) {
  auto& p = ports_.at(port);
  if (field < 0 || field >= static_cast<int>(p.provided.size()) || state < 0 ||
      state >= static_cast<int>(states_.size()))
    throw std::logic_error("port '" + p.name + "': provide() out of range");
  p.provided[field] = state;
}

void UnitSpec::provide_all(int port, int first_state) {
  const int n = static_cast<int>(ports_.at(port).provided.size());
  for (int f = 0; f < n; ++f) provide(port, f, first_state + f);
}

int UnitSpec::add_output(std::string name, std::string unit) {
  outputs_.push_back({std::move(name), std::move(unit)});
  return static_cast<int>(outputs_.size()) - 1;
}

int UnitSpec::state_index(const std::string& name) const {
  for (size_t i = 0; i < states_.size(); ++i)
    if (states_[i].name == name) return static_cast<int>(i);
  return -1;
}

int UnitSpec::param_index(const std::string& name) const {
  for (size_t i = 0; i < params_.size(); ++i)
    if (params_[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string to_string(StreamKind k) {
  switch (k) {
    case StreamKind::Gas:
      return "gas";
    case StreamKind::Liquid:
      return "liquid";
    case StreamKind::Solids:
      return "solids";
    case StreamKind::Heat:
      return "heat";
    case StreamKind::Vapour:
      return "vapour";
    case StreamKind::Holdup:
      return "holdup";
    case StreamKind::Wetting:
      return "wetting";
  }
  return "?";
}

StreamKind stream_kind_from_string(const std::string& s) {
  for (auto k : {StreamKind::Gas, StreamKind::Liquid, StreamKind::Solids, StreamKind::Heat, StreamKind::Vapour,
                 StreamKind::Holdup, StreamKind::Wetting})
    if (to_string(k) == s) return k;
  throw ConfigError("unknown stream kind '" + s + "' (allowed: gas, liquid, solids, heat, vapour, holdup, wetting)");
}

std::string to_string(PortDir d) { return d == PortDir::In ? "in" : d == PortDir::Out ? "out" : "probe"; }

std::vector<FieldSpec> stream_fields(StreamKind kind, int classes) {
  switch (kind) {
    case StreamKind::Gas:
      return {{"mdot", "kg/s"}, {"Y", "kg/kg"}, {"T", "K"}, {"p", "Pa"}};
    case StreamKind::Liquid:
      return {{"mdot", "kg/s"}, {"T", "K"}, {"w", "kg/kg"}};
    case StreamKind::Heat:
      return {{"Q", "W"}, {"T", "K"}};
    case StreamKind::Vapour:
      return {{"mdot", "kg/s"}, {"T", "K"}};
    case StreamKind::Holdup: {
      std::vector<FieldSpec> f;
      for (int i = 0; i < classes; ++i) f.push_back({"mass_" + std::to_string(i), "kg"});
      for (int i = 0; i < classes; ++i) f.push_back({"water_" + std::to_string(i), "kg"});
      f.push_back({"T", "K"});
      f.push_back({"u0", "m/s"});
      return f;
    }
    case StreamKind::Wetting: {
      std::vector<FieldSpec> f;
      for (int i = 0; i < classes; ++i) f.push_back({"mdot_" + std::to_string(i), "kg/s"});
      for (int i = 0; i < classes; ++i) f.push_back({"fwet_" + std::to_string(i), "-"});
      for (int i = 0; i < classes; ++i) f.push_back({"Xwet_" + std::to_string(i), "kg/kg"});
      f.push_back({"T", "K"});
      return f;
    }
    case StreamKind::Solids: {
      std::vector<FieldSpec> f;
      for (int i = 0; i < classes; ++i) f.push_back({"mdot_" + std::to_string(i), "kg/s"});
      for (int i = 0; i < classes; ++i) f.push_back({"X_" + std::to_string(i), "kg/kg"});
      f.push_back({"T", "K"});
      return f;
    }
  }
  return {};
}

std::string to_string(SettingType t) {
  switch (t) {
    case SettingType::Int:
      return "integer";
    case SettingType::Real:
      return "number";
    case SettingType::Bool:
      return "boolean";
    case SettingType::String:
      return "string";
  }
  return "?";
}

std::string setting_to_string(const SettingValue& v) {
  if (auto p = std::get_if<long>(&v)) return std::to_string(*p);
  if (auto p = std::get_if<double>(&v)) return std::to_string(*p);
  if (auto p = std::get_if<bool>(&v)) return *p ? "true" : "false";
  return std::get<std::string>(v);
}

}  // namespace granuflow
