#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Gas phase of a well-mixed process chamber (paper 001, Eqs. (61)-(63)), written in conserved form: water
// vapour mass and enthalpy are the differential states, humidity and temperature algebraic, so the water and
// energy balances close to solver tolerance. Evaporating spray, drying vapour, wall loss and gas-solid heat
// transfer arrive on optional ports: a scene without a mechanism leaves its port open.
void register_chamber_gas(Registry<Unit>& r);
}  // namespace granuflow::units
