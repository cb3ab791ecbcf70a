#include "spray_compartment.hpp"

#include "particle_chamber.hpp"

namespace granuflow::units {

void register_spray_compartment(Registry<Unit>& r) {
  r.add("spray_compartment",
        "spray zone of the two-zone bed: layering, exchange with the drying zone (paper 003, Eqs. 7.37-7.39)",
        [] { return std::make_unique<ParticleChamber>(ChamberRole::kSprayZone); });
}

}  // namespace granuflow::units
