#include "wetting/stokes_report.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

void StokesReport::declare(UnitSpec& s, Settings& st) {
  active_ = st.get_choice("stokes_deformation", "off", {"off", "report"},
                          "report the Stokes deformation regime of colliding d50 granules: off or report (paper 000, "
                          "section 5.6)") == "report";
  if (!active_) return;
  // No value is published for paper 001's plant: the defaults are those of the stokes aggregation kernel.
  const std::string e57 = "user choice as aggregation: stokes (paper 003, Eq. (7.57) gives none)",
                    e58 = "user choice as aggregation: stokes (paper 003, Eq. (7.58) gives none)";
  first_ = s.add_param({"stokes_u_coll", "m/s", 0.5, 0.0, 100.0, "collision velocity", e57});
  s.add_param({"stokes_mu_l", "Pa s", 1e-3, 1e-6, 1e6, "binder viscosity", e57});
  s.add_param({"stokes_h", "m", 10e-6, 1e-9, 1e-2, "thickness of the liquid layer", e58});
  s.add_param({"stokes_h_a", "m", 1e-6, 1e-9, 1e-2, "height of the surface asperities", e58});
  s.add_param({"stokes_e", "-", 0.5, 1e-3, 1.0, "coefficient of restitution", e58});
  o_st_ = s.add_output("stokes_viscous", "-");
  o_coal_ = s.add_output("stokes_coal_critical", "-");
  o_def_ = s.add_output("stokes_def_critical", "-");
  o_regime_ = s.add_output("deformation_regime", "-");
}

}  // namespace granuflow::kernels
