#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Exhaust gas sink: accumulates the dry gas, water and enthalpy that leave, for the balances.
void register_gas_outlet(Registry<Unit>& r);
}  // namespace granuflow::units
