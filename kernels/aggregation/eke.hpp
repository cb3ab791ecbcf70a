// EKE kernel of paper 001, Eq. (37): the collision frequency in the spray zone
//     beta_ij = beta0 (d_i + d_j)^2 sqrt(1/d_i^3 + 1/d_j^3) tau_spray,   beta0 = exp(ln_beta0),
// with d in m and absolute particle numbers (docs/paper001_decisions.md). The formula is
// kernels/wetting/paper001_spray_zone.hpp's collision_frequency(); this wraps it as a registered kernel.
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"
#include "wetting/paper001_spray_zone.hpp"

namespace granuflow::kernels {

class EkeKernel : public PairKernel<EkeKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"ln_beta0", "-", paper001::defaults::kLnBeta0, -60.0, 10.0,
             "ln of the rate constant beta0 (1/s with d in m)", "paper 001, Table 9"},
            {"tau_spray", "-", paper001::defaults::kTauSpray, 0.0, 1.0,
             "fraction of particles residing in the spray zone", "paper 001, Table 9"}};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    return paper001::collision_frequency(T(s.diameter[i]), T(s.diameter[j]), p[0], p[1]);  // Eq. (37), paper 001
  }
};

void register_eke(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
