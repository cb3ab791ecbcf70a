#include "aggregation/glass_transition.hpp"

namespace granuflow::kernels {

std::vector<ParamSpec> GlassTransitionKernel::params() const {
  namespace d = paper001::defaults;
  return {{"ln_beta0", "-", d::kLnBeta0, -60.0, 10.0, "ln of the rate constant beta0 (1/s with d in m)",
           "paper 001, Table 9"},
          {"tau_spray", "-", d::kTauSpray, 0.0, 1.0, "fraction of particles in the spray zone", "paper 001, Table 9"},
          {"d_droplet", "m", d::kDropletDiameter, 1e-7, 1e-3, "droplet diameter", "paper 001, Table 9"},
          {"rho_env", "kg/m3", d::kParticleDensity, 1.0, 1e4, "particle envelope density in Eq. (42)",
           "paper 001, Table 9"},
          {"rho_droplet", "kg/m3", d::kDropletDensity, 1.0, 1e4, "droplet density", "paper 001, Eq. (42)"},
          {"gt_k", "-", d::kGordonTaylorK, 0.01, 100.0, "Gordon-Taylor constant", "paper 001, Table 9"},
          {"tg_liquid", "K", d::kTgLiquid, 1.0, 1000.0, "glass transition of water", "paper 001, Table 9"},
          {"tg_solid", "K", d::kTgSolid, 1.0, 1000.0, "glass transition of the dry solid", "paper 001, Table 9"},
          {"sticky_slope", "K", d::kStickySlope, 0.01, 1000.0, "C1 of Eq. (53)", "paper 001, Table 9"},
          {"sticky_offset", "K", d::kStickyOffset, -200.0, 200.0, "C2 of Eq. (53)", "paper 001, Table 9"}};
}

void register_glass_transition(Registry<AggregationKernel>& r) {
  r.add("glass_transition", "EKE collision frequency x glass-transition success factor (paper 001, Eqs. (37)-(57))",
        [] { return std::make_unique<GlassTransitionKernel>(); });
}

}  // namespace granuflow::kernels
