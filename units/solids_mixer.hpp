#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Mixer of solids streams (seed feed, fines and milled oversize into a granulator): class flows add up, the outlet
// temperature follows from the enthalpy flows.
void register_solids_mixer(Registry<Unit>& r);
}  // namespace granuflow::units
