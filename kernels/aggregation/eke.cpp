#include "aggregation/eke.hpp"

namespace granuflow::kernels {
void register_eke(Registry<AggregationKernel>& r) {
  r.add("eke", "EKE collision frequency in the spray zone (paper 001, Eq. (37))",
        [] { return std::make_unique<EkeKernel>(); });
}
}  // namespace granuflow::kernels
