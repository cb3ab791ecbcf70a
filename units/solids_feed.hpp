#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// A solids feed (seed particles, fresh product) on the flowsheet's size grid: a mass flow with a log-normal mass
// distribution, a moisture and a temperature.
void register_solids_feed(Registry<Unit>& r);
}  // namespace granuflow::units
