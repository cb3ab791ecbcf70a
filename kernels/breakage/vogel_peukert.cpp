#include "breakage/vogel_peukert.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

std::vector<ParamSpec> VogelPeukertSelection::params() const {
  namespace d = paper001::defaults;
  const std::string t10 = "paper 001, Table 10";
  return {{"k_break", "1/s", d::kBreakageRate, 0.0, 10.0, "breakage rate constant k', Eq. (92)", t10},
          {"d_min_break", "m", d::kBreakageDiameterMin, 1e-7, 1e-2, "minimum diameter for breakage, Eq. (92)", t10},
          {"f_mat", "-", d::kMaterialParameter, 0.0, 100.0, "material parameter f_Mat, Eq. (92)", t10},
          {"E_min", "J/kg", d::kBreakageEnergyMin, 0.0, 100.0, "mass-based threshold energy, Eq. (92)", t10}};
}

void VogelPeukertSelection::declare(Settings& s, const std::string& prefix) {
  unit_ = paper001::breakage_size_unit_from_string(
      s.get_choice(prefix + "size_unit", "um", {"um", "mm"},
                   "diameter unit of the fit in Eq. (92), paper 001 (docs/paper001_decisions.md: um)"));
}

void register_vogel_peukert(Registry<SelectionRate>& r) {
  r.add("vogel_peukert", "Vogel-Peukert selection rate (paper 001, Eq. (92))",
        [] { return std::make_unique<VogelPeukertSelection>(); });
}

}  // namespace granuflow::kernels
