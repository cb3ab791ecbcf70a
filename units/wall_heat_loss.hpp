#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Heat loss through the wall to the environment, Q = k A (T - T_env) (paper 001, Eq. (84)), on a heat port.
void register_wall_heat_loss(Registry<Unit>& r);
}  // namespace granuflow::units
