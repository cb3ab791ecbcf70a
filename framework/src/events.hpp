// The scene's `events` and `checkpoints` keys (events.hpp for what they mean): read from YAML and checked against the
// flowsheet, every mistake a ConfigError naming the file, the event, the value and what is allowed.
#pragma once
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "granuflow/events.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow::detail {

std::vector<EventSpec> load_events(const YAML::Node& node, const Flowsheet& fs, const std::string& label);
std::vector<double> load_checkpoints(const YAML::Node& node, const std::string& label);

// Where an event's quantity lives: a state (index into the full state vector) or a reported output.
struct EventQuantity {
  int state = -1;
  int output = -1;
  std::string unit;  // its SI unit
};
// Resolves "unit.state" or "unit.output" (a state first); ConfigError naming `where` for an unknown name or an output
// that integrates a flow (a quadrature: the root finding sees the integrator's states only).
EventQuantity find_event_quantity(const Flowsheet& fs, const std::string& name, const std::string& where);

// The run-time checks of SimOptions::events against the flowsheet and the sensitivity parameters.
void check_events(const Flowsheet& fs, const std::vector<EventSpec>& events, const std::vector<std::string>& sens);

}  // namespace granuflow::detail
