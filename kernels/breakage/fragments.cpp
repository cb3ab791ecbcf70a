#include "breakage/fragments.hpp"

namespace granuflow::kernels {
void register_fragments(Registry<FragmentDistribution>& r) {
  r.add("uniform_binary", "two fragments uniform in volume, b = 2/u (Ziff & McGrady)",
        [] { return std::make_unique<UniformBinaryFragments>(); });
  r.add("power_law", "cumulative volume fraction (v/u)^p", [] { return std::make_unique<PowerLawFragments>(); });
  r.add("tanh_power_law", "power law in d/d_parent with tanh cut-off (paper 001, Eq. (93))",
        [] { return std::make_unique<TanhPowerLawFragments>(); });
}
}  // namespace granuflow::kernels
