#include "aggregation/product.hpp"

namespace granuflow::kernels {
void register_product(Registry<AggregationKernel>& r) {
  r.add("product", "beta = beta0 u v / v_ref^2", [] { return std::make_unique<ProductKernel>(); });
}
}  // namespace granuflow::kernels
