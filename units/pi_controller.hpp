#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// PI controller with a clamped output and back-calculation anti-windup: measures a state or output of one unit and
// drives a parameter of another (signals.hpp; docs/controllers.md).
void register_pi_controller(Registry<Unit>& r);
}  // namespace granuflow::units
