#include "registry.hpp"

#include "liquid_feed.hpp"
#include "liquid_mixer.hpp"
#include "liquid_product.hpp"
#include "liquid_splitter.hpp"
#include "stirred_tank.hpp"

namespace granuflow::units {

void register_all(Registry<Unit>& r) {
  register_liquid_feed(r);
  register_liquid_mixer(r);
  register_liquid_splitter(r);
  register_liquid_product(r);
  register_stirred_tank(r);
}

const Registry<Unit>& builtin() {
  static const Registry<Unit> r = [] {
    Registry<Unit> reg("unit type");
    register_all(reg);
    return reg;
  }();
  return r;
}

}  // namespace granuflow::units
