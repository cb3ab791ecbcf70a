#include "growth/growth_laws.hpp"

#include <cmath>

namespace granuflow::kernels {

std::vector<ParamSpec> MomentBasedGrowth::params() const {
  std::vector<ParamSpec> p{
      {"m_dot", "kg/s", 1e-3, 0.0, 1e3, "solids mass flow sprayed onto the particles, M_sus", "paper 003, Eq. (7.35)"},
      {"rho_s", "kg/m3", 1000.0, 1.0, 1e5, "density of the solidified layer", "paper 003, Eq. (7.35)"}};
  for (int k = 0; k < kMoments; ++k)
    p.push_back({"lambda_" + std::to_string(k), "-", k == 2 ? 1.0 : 0.0, 0.0, 1.0,
                 "weight of the growth law based on moment mu_" + std::to_string(k), "paper 003, Eq. (7.36)"});
  return p;
}

void MomentBasedGrowth::check(const ClassState<double>&, const double* p, const std::string& where) const {
  double sum = 0;
  for (int k = 0; k < kMoments; ++k) sum += p[2 + k];
  if (std::abs(sum - 1.0) > 1e-12)
    throw ConfigError(violation(where + " lambda_0 + ... + lambda_3", sum, "-",
                                "sum = 1 (mass conservation, paper 003, Eq. (7.36))"));
}

void register_growth_laws(Registry<GrowthLaw>& r) {
  r.add("constant", "G = G0, prescribed diameter growth rate", [] { return std::make_unique<ConstantGrowth>(); });
  r.add("surface_proportional", "G = 2 M_sus / (rho_s pi mu_2) (paper 003, Eq. (7.33))",
        [] { return std::make_unique<SurfaceProportionalGrowth>(); });
  r.add("moment_based", "G = sum_k lambda_k 2 M_sus d^(k-2) / (rho_s pi mu_k) (paper 003, Eqs. (7.35)-(7.36))",
        [] { return std::make_unique<MomentBasedGrowth>(); });
}

}  // namespace granuflow::kernels
