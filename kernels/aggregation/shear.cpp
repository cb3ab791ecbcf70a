#include "aggregation/shear.hpp"

namespace granuflow::kernels {
void register_shear(Registry<AggregationKernel>& r) {
  r.add("shear", "beta = shear_rate (d_i + d_j)^3 / (6 V) (orthokinetic)",
        [] { return std::make_unique<ShearKernel>(); });
}
}  // namespace granuflow::kernels
