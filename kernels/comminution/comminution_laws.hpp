// Comminution laws (comminution_law.hpp gives the contract):
//  * lognormal: every parent is ground towards one product distribution, log-normal in mass with median d50 and
//    geometric standard deviation sigma_g, cut off at the parent (the part of the product distribution coarser than
//    the parent's lower class edge stays in the parent's class): a mill set by its product fineness, the usual
//    assumption of sieve-mill recycle studies (e.g. Heinrich et al. 2003);
//  * vogel_peukert: one pass of impact comminution after Vogel & Peukert (2003): a particle of size D breaks with the
//    probability S = 1 - exp(-f_Mat D k (W_m - W_m,min)), W_m,min = (D W_m,min)_ref / D (the product of size and
//    threshold energy is a material constant), 0 below the threshold; broken particles give fragments with the
//    cumulative mass fraction (d / D)^q; unbroken ones pass unchanged.
#pragma once
#include <cmath>

#include "comminution/comminution_law.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class LognormalMill : public ComminutionLawT<LognormalMill> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"d50", "m", 300e-6, 1e-7, 1.0, "mass median diameter of the mill product", "operating input"},
            {"sigma_g", "-", 1.5, 1.01, 10.0, "geometric standard deviation of the mill product", "operating input"}};
  }
  bool parent_independent() const override { return true; }
  template <class T>
  T broken(double, const T*) const {
    return T(1.0);
  }
  template <class T>
  T finer(double d, double, const T* p) const {
    using std::erfc, std::log;
    return 0.5 * erfc(-log(d / p[0]) / (log(p[1]) * std::sqrt(2.0)));
  }
};

class VogelPeukertMill : public ComminutionLawT<VogelPeukertMill> {
 public:
  // Vogel & Peukert's f_Mat (kg/(J m)) and x W_m,min (J m/kg) enter through values at a reference size d_ref:
  // f_Mat = 1 / (E_mat d_ref) and x W_m,min = W_min d_ref, so every parameter has a plain SI unit.
  std::vector<ParamSpec> params() const override {
    const std::string vp = "Vogel & Peukert (2003)";
    return {{"W_m", "J/kg", 200.0, 0.0, 1e7, "mass-specific impact energy per stressing event", "operating input"},
            {"d_ref", "m", 1e-3, 1e-7, 1.0, "reference size of E_mat and W_min", vp},
            {"E_mat", "J/kg", 200.0, 1e-6, 1e9, "material energy at d_ref, 1 / (f_Mat d_ref)", vp},
            {"W_min", "J/kg", 50.0, 0.0, 1e9, "threshold energy at d_ref (W_m,min scales as 1 / D)", vp},
            {"impacts", "-", 1.0, 0.0, 1e4, "stressing events per passage, k", "operating input"},
            {"q", "-", 1.5, 0.05, 10.0, "exponent of the fragments' cumulative mass fraction (d/D)^q", vp}};
  }
  template <class T>
  T broken(double D, const T* p) const {
    using std::exp;
    const T excess = p[0] - p[3] * p[1] / D;  // W_m - W_m,min(D)
    if (!(excess > 0.0)) return T(0.0);
    return 1.0 - exp(-(D / p[1]) * p[4] * excess / p[2]);
  }
  template <class T>
  T finer(double d, double D, const T* p) const {
    using std::pow;
    return pow(T(d / D), p[5]);
  }
};

void register_comminution_laws(Registry<ComminutionLaw>& r);

}  // namespace granuflow::kernels
