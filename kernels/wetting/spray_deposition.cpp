#include "wetting/spray_deposition.hpp"

#include "granuflow/flowsheet.hpp"
#include "paper001_defaults.hpp"

namespace granuflow::kernels {

void SprayDeposition::declare(UnitSpec& s, Settings& st) {
  active_ = st.get_choice("spray_deposition", "spray_zone", {"spray_zone", "filtration"},
                          "droplets reaching the bed: spray_zone (all land on particles) or filtration (a clean-bed "
                          "filter deposits a share, the rest evaporates in the gas; paper 000, sections 5.1.4, "
                          "5.5)") == "filtration";
  if (!active_) return;
  namespace def = paper001::defaults;
  first_ = s.add_param({"filtration_phi_p", "-", 0.1, 1e-3, 0.6, "solids volume fraction the spray passes through",
                        "user choice: none is published for paper 001's plant (paper 000, section 5.1.4)"});
  s.add_param({"filtration_length", "m", def::kSprayZoneDiameter, 1e-6, 10.0,
               "droplets' path through the bed (read as the spray-zone diameter)", "paper 001, Table 9"});
  s.add_param({"filtration_d_drop", "m", def::kDropletDiameter, 1e-7, 1e-3, "droplet diameter", "paper 001, Table 9"});
  s.add_param(
      {"filtration_rho_drop", "kg/m3", def::kLiquidDensity, 500.0, 2000.0, "droplet density", "paper 001, Table 6"});
  o_share_ = s.add_output("filtered_fraction", "-");  // of the droplets reaching the bed, deposited on particles
}

void SprayDeposition::declare_reductions(UnitSpec& s) {
  if (!active_) return;
  r_mass_ = s.add_reduction("filtration: bed mass");
  r_weighted_ = s.add_reduction("filtration: collector efficiency");
}

}  // namespace granuflow::kernels
