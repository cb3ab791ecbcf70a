#include "registry.hpp"

#include <cstdlib>

#include "chamber_gas.hpp"
#include "droplet_evaporation.hpp"
#include "drying_compartment.hpp"
#include "fluid_bed.hpp"
#include "gas_inlet.hpp"
#include "gas_outlet.hpp"
#include "granulator.hpp"
#include "liquid_feed.hpp"
#include "liquid_mixer.hpp"
#include "liquid_product.hpp"
#include "liquid_splitter.hpp"
#include "mill.hpp"
#include "particles.hpp"
#include "pbm_2d.hpp"
#include "pbm_batch.hpp"
#include "pi_controller.hpp"
#include "sieve.hpp"
#include "solids_feed.hpp"
#include "solids_mixer.hpp"
#include "solids_product.hpp"
#include "solids_splitter.hpp"
#include "spray_compartment.hpp"
#include "spray_nozzle.hpp"
#include "spray_zone.hpp"
#include "stirred_tank.hpp"
#include "wall_heat_loss.hpp"

namespace granuflow::units {

void register_all(Registry<Unit>& r) {
  register_particles(r);
  register_liquid_feed(r);
  register_liquid_mixer(r);
  register_liquid_splitter(r);
  register_liquid_product(r);
  register_stirred_tank(r);
  register_pbm_batch(r);
  register_pbm_2d(r);
  register_chamber_gas(r);
  register_droplet_evaporation(r);
  register_fluid_bed(r);
  register_gas_inlet(r);
  register_gas_outlet(r);
  register_solids_feed(r);
  register_solids_product(r);
  register_spray_nozzle(r);
  register_spray_zone(r);
  register_wall_heat_loss(r);
  register_granulator(r);
  register_spray_compartment(r);
  register_drying_compartment(r);
  register_sieve(r);
  register_mill(r);
  register_solids_mixer(r);
  register_solids_splitter(r);
  register_pi_controller(r);
}

#ifdef GRANUFLOW_TEST_UNITS
void register_test_units(Registry<Unit>& r);  // tests/cpp/leaky_pipe.cpp, built with the tests
#endif

const Registry<Unit>& builtin() { return registry(); }

Registry<Unit>& registry() {
  static Registry<Unit> r = [] {
    Registry<Unit> reg("unit type");
    register_all(reg);
#ifdef GRANUFLOW_TEST_UNITS
    if (std::getenv("GRANUFLOW_TEST_UNITS")) register_test_units(reg);  // never in a scene users run
#endif
    return reg;
  }();
  return r;
}

}  // namespace granuflow::units
