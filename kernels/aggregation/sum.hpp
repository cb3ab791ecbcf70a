// Sum kernel beta = beta0 (u + v) / v_ref (Golovin 1963; analytic solution in docs/verification.md). The reference
// volume keeps beta0 in 1/s; beta0 = v_ref = 1 is Golovin's beta = u + v.
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class SumKernel : public PairKernel<SumKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"beta0", "1/s", 1.0, 0.0, 1e6, "rate coefficient at u + v = v_ref", "Golovin 1963"},
            reference_volume_param()};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    return p[0] * (s.volume[i] + s.volume[j]) / p[1];
  }
  int factor_terms(const ClassState<double>& s, const double* p, double* a, double* b) const override {
    const double c = p[0] / p[1];  // K_ij = (c u_i) 1 + c u_j
    for (int i = 0; i < s.n; ++i) a[i] = c * s.volume[i], b[i] = 1.0, a[s.n + i] = c, b[s.n + i] = s.volume[i];
    return 2;
  }
};

void register_sum(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
