// Settings as event actions (events.hpp, docs/events_and_checkpoints.md): a unit declared anew with one setting
// changed and its other settings as in use. Its layout (states, parameters, outputs, ports, quadratures, size classes)
// must be the old one's, name for name, so that the run's unknowns, parameters and sensitivities carry over by
// identity; anything else is refused when the scene is loaded.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/events.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow::detail {

struct RebuiltUnit {
  std::unique_ptr<Unit> unit;
  std::vector<SettingSpec> settings;  // as in use by the new unit
};

// Unit `u` of `fs` declared anew by a.make() with the setting of a.target ("unit.setting") at a.text. ConfigError
// naming `where` for a value the unit refuses, or a layout that differs from the unit's (what differs, and why it
// cannot be carried over).
RebuiltUnit rebuild_unit(const Flowsheet& fs, int u, const EventAction& a, const std::string& where);

// The setting's value as a scene would write it (a number with all its digits).
std::string setting_text(const SettingSpec& s);

}  // namespace granuflow::detail
