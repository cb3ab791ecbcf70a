#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// The drying zone of the two-compartment model of paper 003 (Eq. (7.38), Fig. 7.47): no spray; particles return to
// the spray zone at the rate 1/tau, where by Eq. (7.39) tau_drying / tau_spray = (1 - alpha) / alpha (alpha: the
// spray zone's volume fraction). The sprayed water they carry dries here (drying: first_order); a feed and a discharge
// make the pair a continuous two-zone granulator (units/particle_chamber.hpp).
void register_drying_compartment(Registry<Unit>& r);
}  // namespace granuflow::units
