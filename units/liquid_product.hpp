#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Liquid sink that accumulates the mass, solute and sensible enthalpy (above 0 degC, constant cp) that leave.
void register_liquid_product(Registry<Unit>& r);
}  // namespace granuflow::units
