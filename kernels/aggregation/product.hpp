// Product kernel beta = beta0 u v / v_ref^2 (gels at finite time; analytic moments before gelation in
// docs/verification.md). beta0 = v_ref = 1 is beta = u v.
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class ProductKernel : public PairKernel<ProductKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"beta0", "1/s", 1.0, 0.0, 1e6, "rate coefficient at u = v = v_ref", "McLeod 1962"},
            reference_volume_param()};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    return p[0] * (s.volume[i] / p[1]) * (s.volume[j] / p[1]);
  }
  int factor_terms(const ClassState<double>& s, const double* p, double* a, double* b) const override {
    for (int i = 0; i < s.n; ++i) a[i] = p[0] * (s.volume[i] / p[1]), b[i] = s.volume[i] / p[1];
    return 1;
  }
};

void register_product(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
