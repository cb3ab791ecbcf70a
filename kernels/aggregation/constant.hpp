// Constant kernel beta = beta0 (Smoluchowski; Scott 1968 gives the analytic solution used in the tests).
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class ConstantKernel : public PairKernel<ConstantKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"beta0", "1/s", 1.0, 0.0, 1e6, "rate coefficient per pair of particles", "Smoluchowski 1917"}};
  }
  template <class T>
  T factor(const ClassState<T>&, int, int, const T* p) const {
    return p[0];
  }
  int factor_terms(const ClassState<double>& s, const double* p, double* a, double* b) const override {
    for (int i = 0; i < s.n; ++i) a[i] = p[0], b[i] = 1.0;
    return 1;
  }
};

void register_constant(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
