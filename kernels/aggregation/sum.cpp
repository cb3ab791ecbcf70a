#include "aggregation/sum.hpp"

namespace granuflow::kernels {
void register_sum(Registry<AggregationKernel>& r) {
  r.add("sum", "beta = beta0 (u + v) / v_ref (Golovin)", [] { return std::make_unique<SumKernel>(); });
}
}  // namespace granuflow::kernels
