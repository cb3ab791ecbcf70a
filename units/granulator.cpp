#include "granulator.hpp"

#include "particle_chamber.hpp"

namespace granuflow::units {

void register_granulator(Registry<Unit>& r) {
  r.add("granulator",
        "granulator chamber: layering from a spray (paper 003, Eqs. 7.32-7.34), feed, discharge (free or controlled)",
        [] { return std::make_unique<ParticleChamber>(ChamberRole::kGranulator); });
}

}  // namespace granuflow::units
