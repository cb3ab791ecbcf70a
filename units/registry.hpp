// The one list of built-in unit models. Adding a unit: its file pair, one line here, one in CMakeLists.txt.
#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"

namespace granuflow::units {
void register_all(Registry<Unit>& r);
// The registry with every built-in unit, created on first use, and the unit types of plugins loaded since
// (granuflow/plugin.hpp). registry() is what a plugin's registration function adds to.
const Registry<Unit>& builtin();
Registry<Unit>& registry();
}  // namespace granuflow::units
