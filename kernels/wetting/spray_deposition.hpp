// Droplet deposition as continuum spray filtration (paper 000, sections 5.1.4 and 5.5), a closure a spray-wetted bed
// chooses by its setting spray_deposition. `spray_zone` (the default) keeps the unit's own wetting: every droplet
// that reaches the bed lands on a particle. `filtration` lets the bed filter the droplets as a clean-bed filter
// (Kolakaluri et al., as the review prints it; spray_filtration.hpp) over a path of length L: a share
//     F = 1 - exp(-lambda L),     lambda = sum_i eta_s,i (3/2) phi_p,i / D_i,     phi_p,i = phi_p M_i / M,
// lands on the particles (each class its usual share scaled by F), and the droplets that pass unfiltered evaporate in
// the gas (Li et al.'s assumption, paper 000, section 5.5): their water leaves with the bed's vapour, its latent
// heat drawn from the bed's enthalpy (the solids replenish it from the gas by heat transfer), so that water and energy
// balances close as before. Their dissolved solids dry to dust the bed collects, layered like the deposit's.
// The slip |u_f - u_p| is the interstitial gas velocity u0 / phi_f (the particles at rest on average); the classes
// share one envelope density, so a class's share of the solids volume is its share of the dry mass.
#pragma once
#include <string>

#include "granuflow/properties.hpp"
#include "granuflow/unit.hpp"
#include "wetting/spray_filtration.hpp"

namespace granuflow::kernels {

class SprayDeposition {
 public:
  // Declares the setting and, for `filtration`, the parameters filtration_phi_p, _length, _d_drop, _rho_drop.
  void declare(UnitSpec& s, Settings& st);
  // The unit's two reductions (the bed's mass, and its mass weighted by eta_s / D), declared after all others.
  void declare_reductions(UnitSpec& s);
  bool active() const { return active_; }

  // Paper 000, section 5.1.4: single-collector efficiency of a particle of diameter d_p.
  template <class T>
  T collector_efficiency(const T& slip, const T& rho_g, const T& mu_g, double d_p, const T* p) const {
    namespace f = filtration;
    const T &phi_p = p[0], phi_f = 1.0 - phi_p, dp(d_p);
    const T st = f::droplet_stokes_number(slip, p[2], p[3], dp, mu_g, phi_f);
    const T re = f::mean_reynolds_number(slip, phi_p, rho_g, dp, mu_g, phi_f);
    return f::single_collector_efficiency(f::effective_stokes_number(st, re, phi_p));
  }

  // The share F of the droplets reaching the bed that its particles filter out, for classes of dry mass M[i] and
  // diameter d[i]; u0 the superficial velocity, t_g, p_g, y the gas. Calls the unit's two reductions, in order
  // (in outputs() they are plain sums).
  template <class T, class C>
  T filtered_share(const C& c, const T& u0, const T& t_g, const T& p_g, const T& y, const T* M, const double* d,
                   int n) const {
    const T* p = &c.par(first_);
    const T rho_g = props::humid_air_density(t_g, p_g, y), mu_g = props::air_viscosity(t_g);
    const T slip = u0 / (1.0 - p[0]);
    auto weighted = [&](int i) { return T(M[i] * collector_efficiency(slip, rho_g, mu_g, d[i], p) / d[i]); };
    const T mass = c.reduce(r_mass_, n, [&](int i) { return M[i]; });
    const T sum = c.reduce(r_weighted_, n, weighted);
    const T lambda = filtration::filtration_coefficient(T(sum / mass), p[0], T(1.0));  // phi_p,i = phi_p M_i / M
    return filtration::filtered_fraction(lambda, p[1]);
  }
  // The output filtered_fraction: F at the reported state.
  template <class T, class C>
  void outputs(const C& c, const T& u0, const T& t_g, const T& p_g, const T& y, const T* M, const double* d,
               int n) const {
    if (active_) c.out(o_share_) = filtered_share(c, u0, t_g, p_g, y, M, d, n);
  }

 private:
  bool active_ = false;
  ParamId first_;
  ReductionId r_mass_, r_weighted_;
  OutputId o_share_;
};

}  // namespace granuflow::kernels
