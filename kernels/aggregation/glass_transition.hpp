// Glass-transition success-factor kernel of paper 001, Eqs. (37)-(57):
//     beta_ij = C_f,spray(d_i, d_j) psi_geom(f_wet,i, f_wet,j) psi_phys(P_i, P_j)       (Eq. (39))
// with the surface coverage f_wet,i of the Kariuki coating number of the class's liquid loading X_i
// (Eqs. (40)-(42), (50)-(51)) and the stickiness P_i of the wet spot, whose glass transition follows
// Gordon-Taylor on the spot moisture (Eqs. (52)-(55)). The closures are those of
// kernels/wetting/paper001_spray_zone.hpp; the unit supplies per-class moisture, spot moisture and temperature.
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"
#include "wetting/paper001_spray_zone.hpp"

namespace granuflow::kernels {

class GlassTransitionKernel : public PairKernel<GlassTransitionKernel> {
 public:
  std::vector<ParamSpec> params() const override;
  ClassNeeds needs() const override {
    ClassNeeds n;
    n.moisture = n.spot_moisture = n.temperature = true;
    return n;
  }
  template <class T>
  T pair(const ClassState<T>& s, int i, int j, const T* p) const {
    using namespace paper001;
    const T cf = collision_frequency(T(s.diameter[i]), T(s.diameter[j]), p[0], p[1]);  // Eq. (37)
    const T psi_geom = geometric_success_factor(wet(s, i, p), wet(s, j, p));           // Eq. (40)
    const T psi_phys = physical_success_factor(sticky(s, i, p), sticky(s, j, p));      // Eq. (52)
    return agglomeration_kernel(cf, psi_geom, psi_phys);                               // Eq. (39)
  }

 private:
  template <class T>
  T wet(const ClassState<T>& s, int i, const T* p) const {  // Eqs. (41)-(42), paper 001
    return paper001::surface_coverage(paper001::coating_number(s.moisture[i], T(s.diameter[i]), p[2], p[3], p[4]));
  }
  template <class T>
  T sticky(const ClassState<T>& s, int i, const T* p) const {  // Eqs. (53)-(54), paper 001
    return paper001::sticky_probability(s.temperature[i], paper001::gordon_taylor(s.spot_moisture[i], p[5], p[6], p[7]),
                                        p[8], p[9]);
  }
};

void register_glass_transition(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
