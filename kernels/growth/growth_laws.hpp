// Growth laws (growth_law.hpp gives the contract):
//  * constant: G = G0, m/s, prescribed and size independent (the analytic shifted-distribution case);
//  * surface_proportional: paper 003, Eq. (7.33), G = 2 M_sus / (rho_s pi mu_2): size independent, the
//    sprayed solids M_sus (kg/s) spread over the particle surface; volume-normalized, so the population gains
//    exactly M_sus / rho_s m^3/s;
//  * moment_based: paper 003, Eqs. (7.35)-(7.36), G(d) = sum_k lambda_k 2 M_sus d^(k-2) / (rho_s pi mu_k),
//    k = 0..3, sum_k lambda_k = 1 (lambda_2 = 1 is Eq. (7.33), lambda_3 = 1 volume-proportional growth).
#pragma once
#include <cmath>
#include <string>

#include "granuflow/errors.hpp"
#include "granuflow/registry.hpp"
#include "growth/growth_law.hpp"

namespace granuflow::kernels {

class ConstantGrowth : public GrowthLawT<ConstantGrowth> {
 public:
  bool volume_normalized() const override { return false; }
  std::vector<ParamSpec> params() const override {
    return {{"G", "m/s", 1e-6, -1.0, 1.0, "growth rate of the diameter", "paper 003, Eq. (7.34)"}};
  }
  template <class T>
  void eval(const double*, int nf, const T* p, T* shape, T* amount) const {
    for (int f = 0; f < nf; ++f) shape[f] = T(1.0);
    amount[0] = p[0];
  }
};

class SurfaceProportionalGrowth : public GrowthLawT<SurfaceProportionalGrowth> {
 public:
  bool volume_normalized() const override { return true; }
  std::vector<ParamSpec> params() const override {
    return {{"m_dot", "kg/s", 1e-3, 0.0, 1e3, "solids mass flow sprayed onto the particles, M_sus",
             "paper 003, Eq. (7.33)"},
            {"rho_s", "kg/m3", 1000.0, 1.0, 1e5, "density of the solidified layer", "paper 003, Eq. (7.33)"}};
  }
  template <class T>
  void eval(const double*, int nf, const T* p, T* shape, T* amount) const {
    for (int f = 0; f < nf; ++f) shape[f] = T(1.0);
    amount[0] = p[0] / p[1];  // Eq. (7.33), paper 003: volume delivered per second
  }
};

class MomentBasedGrowth : public GrowthLawT<MomentBasedGrowth> {
 public:
  static constexpr int kMoments = 4;  // k = 0..3
  bool volume_normalized() const override { return true; }
  int terms() const override { return kMoments; }
  std::vector<ParamSpec> params() const override;
  void check(const ClassState<double>& s, const double* p, const std::string& where) const override;
  template <class T>
  void eval(const double* d, int nf, const T* p, T* shape, T* amount) const {
    for (int k = 0; k < kMoments; ++k) {
      for (int f = 0; f < nf; ++f) shape[size_t(k) * nf + f] = T(std::pow(d[f], k - 2));  // Eq. (7.35), paper 003
      amount[k] = p[2 + k] * p[0] / p[1];                                                 // Eq. (7.36), paper 003
    }
  }
};

void register_growth_laws(Registry<GrowthLaw>& r);

}  // namespace granuflow::kernels
