#include "drying_compartment.hpp"

#include "particle_chamber.hpp"

namespace granuflow::units {

void register_drying_compartment(Registry<Unit>& r) {
  r.add("drying_compartment",
        "drying zone of the two-zone bed: exchange with the spray zone, drying, feed, discharge (paper 003)",
        [] { return std::make_unique<ParticleChamber>(ChamberRole::kDryingZone); });
}

}  // namespace granuflow::units
