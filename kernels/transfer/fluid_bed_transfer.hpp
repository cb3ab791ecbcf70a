// Fluid-bed hydrodynamics and gas-particle heat and mass transfer used by paper 001:
// Wen-Yu minimum fluidization (Eqs. (31)-(33)), Reynolds numbers (Eqs. (30), (76), (77)),
// Ranz-Marshall single-particle Sherwood and Nusselt numbers (Eqs. (75), (88)) and their bed forms after
// Burgschweiger & Tsotsas (Eqs. (73), (74), (86), (87)).
//
// Templates on the scalar type T (double or ceres::Jet); SI units; all dimensionless groups use diameters in m.
// In Eqs. (74) and (87) the paper writes A_i/A_inlet in one place and A_p/A_inlet in the other; both are the
// total particle surface of the bed over the distributor cross-section (docs/paper001_decisions.md), see
// bed_area_ratio().
#pragma once
#include <cmath>

#include "granuflow/properties.hpp"

namespace granuflow::kernels::transfer {

// Eq. (33), paper 001.
template <class T>
T archimedes_number(const T& d, const T& rho_p, const T& rho_g, const T& mu) {
  return rho_g * d * d * d * (rho_p - rho_g) * props::kGravity / (mu * mu);
}

// Eq. (32), paper 001 (Wen & Yu): the positive root of 24.5 Re^2 + 1650 Re = Ar, written as
// 2 Ar / (1650 + sqrt(1650^2 + 98 Ar)), the same root without the cancellation of -1650 + sqrt(...) at small Ar.
template <class T>
T wen_yu_reynolds_mf(const T& ar) {
  using std::sqrt;
  return 2.0 * ar / (1650.0 + sqrt(1650.0 * 1650.0 + 4.0 * 24.5 * ar));
}

// Eq. (31), paper 001.
template <class T>
T minimum_fluidization_velocity(const T& re_mf, const T& nu_g, const T& d) {
  return re_mf * nu_g / d;
}

// Eqs. (31)-(33), paper 001, composed: u_mf of a particle of diameter d and density rho_p in a gas.
template <class T>
T wen_yu_umf(const T& d, const T& rho_p, const T& rho_g, const T& mu) {
  return minimum_fluidization_velocity(wen_yu_reynolds_mf(archimedes_number(d, rho_p, rho_g, mu)),
                                       props::kinematic_viscosity(mu, rho_g), d);
}

// Eq. (30), paper 001: excess-gas Reynolds number that drives the DEM surrogates (Eqs. (29), (47), (49)).
template <class T>
T excess_reynolds_number(const T& u_inlet, const T& u_mf, const T& d, const T& nu_g) {
  return (u_inlet - u_mf) * d / nu_g;
}

// Eq. (76), paper 001.
template <class T>
T particle_reynolds_number(const T& u0, const T& d, const T& nu_g) {
  return u0 * d / nu_g;
}

// Eq. (77), paper 001.
template <class T>
T superficial_velocity(const T& volume_flow, const T& a_inlet) {
  return volume_flow / a_inlet;
}

// Common form of Eqs. (75) and (88), paper 001 (Ranz & Marshall), from sqrt(Re) and the cube root of Sc (for Sh) or
// Pr (for Nu): a bed's size classes share Sc and Pr, and Sh and Nu of a class share Re, so callers take the roots once.
template <class T>
T ranz_marshall_roots(const T& sqrt_re, const T& cbrt_sc_or_pr) {
  return 2.0 + 0.6 * sqrt_re * cbrt_sc_or_pr;
}
// The same from Re and Sc or Pr. Not differentiable at Re = 0 (sqrt), which a flowing bed never reaches.
template <class T>
T ranz_marshall(const T& re, const T& sc_or_pr) {
  using std::cbrt;
  using std::sqrt;
  return ranz_marshall_roots(sqrt(re), cbrt(sc_or_pr));
}

// Eq. (75), paper 001.
template <class T>
T sherwood_single(const T& re0, const T& sc) {
  return ranz_marshall(re0, sc);
}

// Eq. (88), paper 001.
template <class T>
T nusselt_single(const T& re0, const T& pr) {
  return ranz_marshall(re0, pr);
}

// A_p / A_inlet of Eqs. (74) and (87): total particle surface of the bed (sum N_i pi d_i^2) over the
// distributor cross-section.
template <class T>
T bed_area_ratio(const T& total_particle_surface, const T& a_inlet) {
  return total_particle_surface / a_inlet;
}

// Common form of Eqs. (74) and (87), paper 001: Re X / a * ln(1 + single a / (Re X)); log1p keeps the
// small-area limit (-> single) accurate.
template <class T>
T bulk_transfer_number(const T& single, const T& re0, const T& sc_or_pr, const T& area_ratio) {
  using std::log1p;
  const T pe = re0 * sc_or_pr;
  return pe / area_ratio * log1p(single * area_ratio / pe);
}

// Eq. (74), paper 001: eps is the bulk Sherwood correction factor (Table 8: 1).
template <class T>
T bulk_sherwood(const T& sh, const T& re0, const T& sc, const T& area_ratio, const T& eps = T(1.0)) {
  return eps * bulk_transfer_number(sh, re0, sc, area_ratio);
}

// Eq. (87), paper 001.
template <class T>
T bulk_nusselt(const T& nu, const T& re0, const T& pr, const T& area_ratio) {
  return bulk_transfer_number(nu, re0, pr, area_ratio);
}

// Eq. (73), paper 001: m/s.
template <class T>
T mass_transfer_coefficient(const T& sh_bulk, const T& diffusivity, const T& d) {
  return sh_bulk * diffusivity / d;
}

// Eq. (86), paper 001: W/(m^2 K).
template <class T>
T heat_transfer_coefficient(const T& nu_bulk, const T& lambda_g, const T& d) {
  return nu_bulk * lambda_g / d;
}

}  // namespace granuflow::kernels::transfer
