#include "aggregation/glass_transition.hpp"

#include <vector>

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

std::vector<ParamSpec> GlassTransitionKernel::params() const {
  namespace d = paper001::defaults;
  const std::string t9 = "paper 001, Table 9";
  std::vector<ParamSpec> v = {
      // Upper bound -5: at -10 the headline bed already agglomerates everything into the top class within the hour,
      // and from about 0 no run can start (consistent initialization fails on the birth rates).
      {"ln_beta0", "-", d::kLnBeta0, -60.0, -5.0, "ln of the agglomeration rate constant (beta0 in 1/s with d in m)",
       t9},
      {"tau_spray", "-", d::kTauSpray, 0.0, 1.0, "fraction of particles in the spray zone, Eq. (37)", t9},
      {"gt_k", "-", d::kGordonTaylorK, 0.01, 100.0, "Gordon-Taylor constant, Eq. (54)", t9},
      {"Tg_liquid", "K", d::kTgLiquid, 50.0, 400.0, "glass transition of water, Eq. (54)", t9},
      {"Tg_solid", "K", d::kTgSolid, 200.0, 700.0, "glass transition of the dry solid, Eq. (54)", t9},
      {"sticky_slope", "K", d::kStickySlope, 0.1, 200.0, "width of the sticky transition, Eq. (53)", t9},
      {"sticky_offset", "K", d::kStickyOffset, -200.0, 200.0, "sticky point above Tg, Eq. (53)", t9}};
  if (per_volume_)
    v.push_back({"V_vessel", "m3", d::kEquipmentVolume, 1e-3, 1e3, "vessel volume (beta0 per m3 of vessel)",
                 "paper 001, Table 6"});
  return v;
}

void GlassTransitionKernel::declare(Settings& s, const std::string& prefix) {
  per_volume_ = s.get_choice(prefix + "beta0_basis", "absolute", {"absolute", "per_m3"},
                             "beta0 for absolute particle numbers (default, docs/paper001_decisions.md) or per m3 of "
                             "vessel") == "per_m3";
}

void GlassTransitionKernel::efficiencies(const double* phi, int n, const double*, double* E) const {
  std::vector<double> u(2 * size_t(n));  // by feature: 1 - f_wet of each class, then 1 - P_sticky
  for (int i = 0; i < n; ++i) u[i] = 1.0 - phi[2 * size_t(i)], u[size_t(n) + i] = 1.0 - phi[2 * size_t(i) + 1];
  const double *u0 = u.data(), *u1 = u.data() + n;
  size_t q = 0;
  for (int i = 0; i < n; q += n - i, ++i) {
    const double a0 = u0[i], a1 = u1[i];
    double* Ei = E + (q - i);                                                     // Ei[j]: pair (i, j)
    for (int j = i; j < n; ++j) Ei[j] = (1.0 - a0 * u0[j]) * (1.0 - a1 * u1[j]);  // Eqs. (40) x (52), paper 001
  }
}

void register_glass_transition(Registry<AggregationKernel>& r) {
  r.add("glass_transition", "EKE collision frequency x glass-transition success factor (paper 001, Eqs. (37)-(57))",
        [] { return std::make_unique<GlassTransitionKernel>(); });
}

}  // namespace granuflow::kernels
