#include "aggregation/constant.hpp"

namespace granuflow::kernels {
void register_constant(Registry<AggregationKernel>& r) {
  r.add("constant", "beta = beta0 (size independent)", [] { return std::make_unique<ConstantKernel>(); });
}
}  // namespace granuflow::kernels
