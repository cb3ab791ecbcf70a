// Shear (orthokinetic) kernel beta_ij = shear_rate (d_i + d_j)^3 / (6 V): Smoluchowski's collision rate
// (4/3) G (r_i + r_j)^3 per unit concentration, divided by the volume V the particles share, so that beta is
// per pair of particles (absolute numbers).
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class ShearKernel : public PairKernel<ShearKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"shear_rate", "1/s", 1.0, 0.0, 1e6, "shear rate of the flow", "Smoluchowski 1917"},
            {"volume", "m3", 1.0, 1e-12, 1e6, "volume shared by the particles", "per-pair basis (absolute numbers)"}};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    const double dd = s.diameter[i] + s.diameter[j];
    return p[0] * (dd * dd * dd / 6.0) / p[1];
  }
};

void register_shear(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
