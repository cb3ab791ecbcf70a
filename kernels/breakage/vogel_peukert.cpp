#include "breakage/vogel_peukert.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

std::vector<ParamSpec> VogelPeukertSelection::params() const {
  namespace d = paper001::defaults;
  return {{"k_break", "1/s", d::kBreakageRate, 0.0, 1e3, "breakage rate constant k'", "paper 001, Table 10"},
          {"d_min", "m", d::kBreakageDiameterMin, 1e-7, 1e-1, "minimum diameter for breakage", "paper 001, Table 10"},
          {"f_mat", "-", d::kMaterialParameter, 0.0, 1e3, "material parameter f_Mat", "paper 001, Table 10"},
          {"e_min", "J/kg", d::kBreakageEnergyMin, 0.0, 1e6, "mass-based threshold energy", "paper 001, Table 10"}};
}

void VogelPeukertSelection::declare(Settings& s, const std::string& prefix) {
  unit_ = paper001::breakage_size_unit_from_string(
      s.get_choice(prefix + "size_unit", "um", {"um", "mm"}, "diameter unit of the fit in Eq. (92), paper 001"));
}

void register_vogel_peukert(Registry<SelectionRate>& r) {
  r.add("vogel_peukert", "Vogel-Peukert selection rate (paper 001, Eq. (92))",
        [] { return std::make_unique<VogelPeukertSelection>(); });
}

}  // namespace granuflow::kernels
