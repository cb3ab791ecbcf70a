#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Fluidization-air inlet: volume flow, temperature and absolute humidity (each a parameter or a piecewise-linear
// input) -> dry-gas mass flow. Also a probe of its state (superficial velocity of closures, paper 001 Eq. (77)).
void register_gas_inlet(Registry<Unit>& r);
}  // namespace granuflow::units
