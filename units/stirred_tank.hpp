#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Heated, ideally mixed liquid tank with constant hold-up: temperature and solute fraction are differential.
void register_stirred_tank(Registry<Unit>& r);
}  // namespace granuflow::units
