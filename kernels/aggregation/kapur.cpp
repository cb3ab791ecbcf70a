#include "aggregation/kapur.hpp"

namespace granuflow::kernels {
void register_kapur(Registry<AggregationKernel>& r) {
  r.add("kapur", "beta = beta0 ((u+v)/v_ref)^a / (u v / v_ref^2)^b", [] { return std::make_unique<KapurKernel>(); });
}
}  // namespace granuflow::kernels
