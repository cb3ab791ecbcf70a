#include "breakage/power_law_selection.hpp"

namespace granuflow::kernels {
void register_power_law_selection(Registry<SelectionRate>& r) {
  r.add("power_law", "S = s0 (v / v_ref)^a", [] { return std::make_unique<PowerLawSelection>(); });
  r.add("linear", "S = s0 v / v_ref (Ziff & McGrady)", [] { return std::make_unique<LinearSelection>(); });
}
}  // namespace granuflow::kernels
