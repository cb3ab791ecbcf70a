// Kapur kernel beta = beta0 ((u + v) / v_ref)^a / (u v / v_ref^2)^b (Kapur 1972, the kernel of balling and
// granulation; a = 1, b = 0 is the sum kernel).
#pragma once
#include <cmath>

#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class KapurKernel : public PairKernel<KapurKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"beta0", "1/s", 1.0, 0.0, 1e6, "rate coefficient", "Kapur 1972"},
            reference_volume_param(),
            {"a", "-", 1.0, 0.0, 5.0, "exponent of the sum of the volumes", "Kapur 1972"},
            {"b", "-", 0.0, 0.0, 5.0, "exponent of the product of the volumes", "Kapur 1972"}};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    using std::pow;
    const T su = (s.volume[i] + s.volume[j]) / p[1], pr = (s.volume[i] / p[1]) * (s.volume[j] / p[1]);
    return p[0] * pow(su, p[2]) / pow(pr, p[3]);
  }
};

void register_kapur(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
