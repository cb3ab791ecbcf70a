#include <charconv>
#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"
#include "granuflow/unit.hpp"

namespace granuflow {

StateId UnitSpec::add_state(std::string name, StateKind kind, std::string unit, double scale) {
  if (state_at_.count(name)) throw std::logic_error("state '" + name + "' declared twice");
  if (!is_known_si_unit(unit)) throw std::logic_error("state '" + name + "' has unknown SI unit '" + unit + "'");
  if (!(scale > 0) || !std::isfinite(scale)) throw std::logic_error("state '" + name + "' needs a positive scale");
  state_at_.emplace(name, static_cast<int>(states_.size()));
  states_.push_back({std::move(name), kind, std::move(unit), scale, false});
  return {static_cast<int>(states_.size()) - 1};
}

StateId UnitSpec::add_accumulator(std::string name, std::string unit, double scale) {
  const StateId id = add_state(std::move(name), StateKind::Differential, std::move(unit), scale);
  states_[id.i].accumulator = true;
  return id;
}

StateId UnitSpec::add_states(const std::string& name, int n, StateKind kind, const std::string& unit, double scale) {
  const StateId first{static_cast<int>(states_.size())};
  for (int i = 0; i < n; ++i) add_state(name + "_" + std::to_string(i), kind, unit, scale);
  return first;
}

void UnitSpec::set_nonnegative(StateId first, int n, bool enforce) {
  for (int i = 0; i < n; ++i) {
    states_.at(first.i + i).nonnegative = true;
    states_.at(first.i + i).enforced = enforce;
  }
}

ParamId UnitSpec::add_param(ParamSpec spec) {
  if (param_index(spec.name) >= 0) throw std::logic_error("parameter '" + spec.name + "' declared twice");
  if (!is_known_si_unit(spec.unit))
    throw std::logic_error("parameter '" + spec.name + "' has unknown SI unit '" + spec.unit + "'");
  if (!(spec.lower <= spec.value && spec.value <= spec.upper))
    throw std::logic_error("parameter '" + spec.name + "' default outside its bounds");
  params_.push_back(std::move(spec));
  return {static_cast<int>(params_.size()) - 1};
}

PortId UnitSpec::add_port(std::string name, StreamKind kind, PortDir dir, int classes, bool optional) {
  for (const auto& p : ports_)
    if (p.name == name) throw std::logic_error("port '" + name + "' declared twice");
  if (!kind) throw std::logic_error("port '" + name + "' has no stream kind");
  PortSpec p{std::move(name), kind, dir, classes, optional, {}, {}, {}};
  const size_t nf = stream_fields(kind, classes).size();
  p.provided.assign(nf, -1);
  p.forwarded.assign(nf, {-1, -1});
  ports_.push_back(std::move(p));
  return {static_cast<int>(ports_.size()) - 1};
}

void UnitSpec::set_port_grid(PortId port, std::vector<double> diameters) {
  if (static_cast<int>(diameters.size()) != ports_.at(port.i).classes)
    throw std::logic_error("port '" + ports_.at(port.i).name + "': grid size differs from its class count");
  ports_.at(port.i).grid = std::move(diameters);
}

void UnitSpec::provide(PortId port, int field, StateId state) {
  auto& p = ports_.at(port.i);
  if (field < 0 || field >= static_cast<int>(p.provided.size()) || state.i < 0 ||
      state.i >= static_cast<int>(states_.size()))
    throw std::logic_error("port '" + p.name + "': provide() out of range");
  p.provided[field] = state.i;
}

void UnitSpec::provide_all(PortId port, StateId first_state) {
  const int n = static_cast<int>(ports_.at(port.i).provided.size());
  for (int f = 0; f < n; ++f) provide(port, f, first_state + f);
}

void UnitSpec::forward(PortId port, int field, PortId in_port, int in_field) {
  auto& p = ports_.at(port.i);
  const auto& in = ports_.at(in_port.i);
  if (p.dir == PortDir::In || in.dir != PortDir::In)
    throw std::logic_error("port '" + p.name + "': forward() passes an inlet's field on to an outlet");
  if (field < 0 || field >= static_cast<int>(p.forwarded.size()) || in_field < 0 ||
      in_field >= static_cast<int>(in.provided.size()))
    throw std::logic_error("port '" + p.name + "': forward() out of range");
  p.forwarded[field] = {in_port.i, in_field};
}

OutputId UnitSpec::add_output(std::string name, std::string unit, OutputRole role, std::string quantity, int cls) {
  for (const auto& o : outputs_)
    if (o.name == name) throw std::logic_error("output '" + name + "' declared twice");
  if (!is_known_si_unit(unit)) throw std::logic_error("output '" + name + "' has unknown SI unit '" + unit + "'");
  const bool balance =
      role == OutputRole::kBalanceIn || role == OutputRole::kBalanceOut || role == OutputRole::kBalanceHold;
  // "solids:<component>": the balance of one named solid of a particle system (particles.hpp)
  if (balance && quantity != "water" && quantity != "solids" && quantity != "energy" &&
      quantity.rfind("solids:", 0) != 0)
    throw std::logic_error("balance output '" + name + "' needs quantity water, solids, solids:<component> or energy");
  outputs_.push_back({std::move(name), std::move(unit), role, std::move(quantity), cls, ""});
  return {static_cast<int>(outputs_.size()) - 1};
}

std::pair<OutputId, OutputId> UnitSpec::add_size_distribution(int n, std::vector<double> diameter_edges) {
  if (!diameter_edges.empty() && diameter_edges.size() != size_t(n) + 1)
    throw std::logic_error("size distribution of " + std::to_string(n) + " classes with " +
                           std::to_string(diameter_edges.size()) + " edges");
  size_edges_ = std::move(diameter_edges);
  const OutputId d{static_cast<int>(outputs_.size())};
  for (int i = 0; i < n; ++i) add_output("psd_d_" + std::to_string(i), "m", OutputRole::kSizeDiameter, "", i);
  const OutputId m{static_cast<int>(outputs_.size())};
  for (int i = 0; i < n; ++i) add_output("psd_m_" + std::to_string(i), "kg", OutputRole::kSizeMass, "", i);
  return {d, m};
}

QuadId UnitSpec::add_quadrature(std::string name, std::string unit, double scale, OutputRole role,
                                std::string quantity) {
  if (!(scale > 0) || !std::isfinite(scale)) throw std::logic_error("quadrature '" + name + "' needs a positive scale");
  const OutputId o = add_output(name, unit, role, std::move(quantity));
  quads_.push_back({std::move(name), std::move(unit), scale, o});
  return {static_cast<int>(quads_.size()) - 1};
}

ReductionId UnitSpec::add_reduction(std::string name) {
  reductions_.push_back(std::move(name));
  return {static_cast<int>(reductions_.size()) - 1};
}

void UnitSpec::set_classes(ClassLayout layout) {
  for (StateId b : layout.state_blocks)
    if (b.i < 0 || b.i + layout.n > static_cast<int>(states_.size()))
      throw std::logic_error("class layout: a state block lies outside the declared states");
  for (auto [port, first] : layout.field_blocks)
    if (port.i < 0 || first < 0 || first + layout.n > static_cast<int>(ports_.at(port.i).provided.size()))
      throw std::logic_error("class layout: a field block lies outside its port");
  classes_ = std::move(layout);
}

int UnitSpec::state_index(const std::string& name) const {
  const auto it = state_at_.find(name);
  return it == state_at_.end() ? -1 : it->second;
}

int UnitSpec::param_index(const std::string& name) const {
  for (size_t i = 0; i < params_.size(); ++i)
    if (params_[i].name == name) return static_cast<int>(i);
  return -1;
}

void UnitSpec::rebase_param(int index, double value, std::string source) {
  ParamSpec& p = params_.at(static_cast<size_t>(index));
  p.value = value;
  p.source = std::move(source);
}

std::string to_string(PortDir d) { return d == PortDir::In ? "in" : d == PortDir::Out ? "out" : "probe"; }

void append_class_fields(std::vector<FieldSpec>& f, const std::string& name, int classes, const std::string& unit) {
  for (int i = 0; i < classes; ++i) f.push_back({name + "_" + std::to_string(i), unit});
}

namespace streams {
StreamKind gas() {
  static const StreamType t{"gas", "dry-gas mass flow, humidity, temperature, pressure", [](int) {
                              return std::vector<FieldSpec>{{"mdot", "kg/s"}, {"Y", "kg/kg"}, {"T", "K"}, {"p", "Pa"}};
                            }};
  return &t;
}
StreamKind liquid() {
  static const StreamType t{"liquid", "mass flow, temperature, dissolved-solids mass fraction", [](int) {
                              return std::vector<FieldSpec>{{"mdot", "kg/s"}, {"T", "K"}, {"w", "kg/kg"}};
                            }};
  return &t;
}
StreamKind heat() {
  static const StreamType t{"heat", "heat flow from the out side to the in side, temperature of the providing side",
                            [](int) {
                              return std::vector<FieldSpec>{{"Q", "W"}, {"T", "K"}};
                            }};
  return &t;
}
StreamKind vapour() {
  static const StreamType t{"vapour", "water-vapour mass flow and its temperature", [](int) {
                              return std::vector<FieldSpec>{{"mdot", "kg/s"}, {"T", "K"}};
                            }};
  return &t;
}
StreamKind solids() {
  static const StreamType t{"solids", "per class dry-solid and water mass flows, temperature", [](int n) {
                              std::vector<FieldSpec> f;
                              append_class_fields(f, "mdot", n, "kg/s");
                              append_class_fields(f, "water", n, "kg/s");
                              f.push_back({"T", "K"});
                              return f;
                            }};
  return &t;
}
namespace {
template <int K>
StreamKind solids_of() {
  static const StreamType t{"solids/" + std::to_string(K) + " components",
                            "per class dry-solid and water mass flows, temperature, per class mass flows of the "
                            "components after the first",
                            [](int n) {
                              std::vector<FieldSpec> f = solids()->fields(n);
                              for (int c = 1; c < K; ++c) append_class_fields(f, "comp" + std::to_string(c), n, "kg/s");
                              return f;
                            }};
  return &t;
}
}  // namespace
StreamKind solids(int components) {
  static_assert(kMaxComponents == 4);
  switch (components) {
    case 2:
      return solids_of<2>();
    case 3:
      return solids_of<3>();
    case 4:
      return solids_of<4>();
    default:
      return solids();
  }
}
}  // namespace streams

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
  if (auto p = std::get_if<double>(&v)) {  // the shortest text that reads back as the same number (1e-09, not 0.000000)
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, *p);
    return std::string(buf, r.ptr);
  }
  if (auto p = std::get_if<bool>(&v)) return *p ? "true" : "false";
  return std::get<std::string>(v);
}

}  // namespace granuflow
