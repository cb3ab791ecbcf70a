#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Adiabatic mixer of N liquid inlets (setting `inlets`), constant heat capacity.
void register_liquid_mixer(Registry<Unit>& r);
}  // namespace granuflow::units
