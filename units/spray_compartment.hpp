#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// The spray zone of the two-compartment model of paper 003 (Eq. (7.37), Fig. 7.47): the particles here receive the
// whole spray and grow by layering; they leave for the drying zone at the rate 1/tau (tau: the mean residence time
// in the spray zone, 4 s in Table 7.7) and come back through `in` (units/particle_chamber.hpp).
void register_spray_compartment(Registry<Unit>& r);
}  // namespace granuflow::units
