#include "aggregation/stokes.hpp"

namespace granuflow::kernels {
void register_stokes(Registry<AggregationKernel>& r) {
  r.add("stokes", "beta0 where the viscous Stokes number is below critical (paper 003, Eqs. (7.57)-(7.58))",
        [] { return std::make_unique<StokesKernel>(); });
}
}  // namespace granuflow::kernels
