#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Spray nozzle: liquid rate, temperature and dissolved-solids fraction, switched on at t_on and off at t_off
// (breakpoints of the integration).
void register_spray_nozzle(Registry<Unit>& r);
}  // namespace granuflow::units
