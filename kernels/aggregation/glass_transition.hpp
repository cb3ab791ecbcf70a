// Glass-transition success-factor kernel of paper 001, Eqs. (37)-(57):
//     beta_ij = C_f,spray(d_i, d_j) psi_geom(f_wet,i, f_wet,j) psi_phys(P_i, P_j)       (Eq. (39))
// with the EKE collision frequency of the spray zone (Eq. (37)), the probability that a collision meets a wet spot
// (Eq. (40)) from the wetted surface fractions f_wet of the partners (Eq. (41), computed by the spray zone from its
// liquid split and the Kariuki coating number, Eqs. (42)-(51)), and the probability that a wet spot is sticky
// (Eq. (52)): its glass transition follows Gordon-Taylor on the wet-spot moisture (Eq. (54)) and the stickiness
// rises over the sticky-point offset (Eq. (53)). The kernel reads the per-class fields wetted fraction, spot
// moisture and temperature; the unit that owns it supplies them (the fluid bed from its spray-zone port, pbm_batch
// from parameters). Setting <prefix>beta0_basis: absolute (beta0 for absolute particle numbers, the default of
// docs/paper001_decisions.md) or per_m3 (beta0 per m^3 of vessel: beta divided by V_vessel).
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"
#include "wetting/paper001_spray_zone.hpp"

namespace granuflow::kernels {

class GlassTransitionKernel : public PairKernel<GlassTransitionKernel> {
 public:
  std::vector<ParamSpec> params() const override;
  void declare(Settings& s, const std::string& prefix) override;
  ClassNeeds needs() const override {
    ClassNeeds n;
    n.wetted_fraction = n.spot_moisture = n.temperature = true;
    return n;
  }
  enum P { kLnBeta0, kTauSpray, kGtK, kTgL, kTgS, kSlope, kOffset, kVessel };
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    const T cf = paper001::collision_frequency(T(s.diameter[i]), T(s.diameter[j]), p[kLnBeta0], p[kTauSpray]);  // (37)
    return per_volume_ ? T(cf / p[kVessel]) : cf;
  }
  static constexpr int kFeatures = 2;  // wetted fraction and stickiness of the wet spot
  template <class T>
  void features(const ClassState<T>& s, int i, const T* p, T* phi) const {
    phi[0] = s.wetted_fraction()[i];
    const T tg = paper001::gordon_taylor(s.spot_moisture()[i], p[kGtK], p[kTgL], p[kTgS]);  // Eq. (54)
    phi[1] = paper001::sticky_probability(s.temperature()[i], tg, p[kSlope], p[kOffset]);   // Eq. (53)
  }
  // E of every pair in doubles as one vector loop per class (1 - f_wet and 1 - P_sticky of each class formed once):
  // the operations of efficiency() pair by pair, to the bit.
  using PairKernel<GlassTransitionKernel>::efficiencies;
  void efficiencies(const double* phi, int n, const double* p, double* E) const override;
  template <class T>
  T efficiency(const T* a, const T* b, const T*) const {
    return paper001::geometric_success_factor(a[0], b[0]) *
           paper001::physical_success_factor(a[1], b[1]);  // (40), (52)
  }

 private:
  bool per_volume_ = false;
};

void register_glass_transition(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
