#include "comminution/comminution_laws.hpp"

namespace granuflow::kernels {

void register_comminution_laws(Registry<ComminutionLaw>& r) {
  r.add("lognormal", "product log-normal in mass (d50, sigma_g), cut off at the parent",
        [] { return std::make_unique<LognormalMill>(); });
  r.add("vogel_peukert", "impact breakage probability and power-law fragments (Vogel & Peukert 2003)",
        [] { return std::make_unique<VogelPeukertMill>(); });
}

}  // namespace granuflow::kernels
