// Droplet deposition as continuum spray filtration (paper 000, section 5.1.4): the droplets are a component of the
// humid air, filtered by the particles as by a clean-bed filter (Kolakaluri et al.'s DNS correlation, as used by
// Askarishahi et al.). Templates on the scalar type; SI units; phi_p the solids volume fraction, phi_f = 1 - phi_p.
#pragma once
#include <cmath>

namespace granuflow::kernels::filtration {

// Paper 000, section 5.1.4: A(phi_p) = (6 - 6 phi^(5/3)) / (6 - 9 phi^(1/3) + 9 phi^(5/3) - 6 phi^2); A(0) = 1.
template <class T>
T happel_factor(const T& phi_p) {
  using std::cbrt;
  const T c = cbrt(phi_p), c5 = c * c * c * c * c;
  return (6.0 - 6.0 * c5) / (6.0 - 9.0 * c + 9.0 * c5 - 6.0 * phi_p * phi_p);
}

// The review's nu_f in St and Re_m below is the gas's dynamic viscosity mu_f (Pa s): only so are both groups
// dimensionless (docs/drying_closures.md).
// Paper 000, section 5.1.4: droplet Stokes number St = |u_f - u_p| d_d^2 rho_d / (18 D_p mu_f phi_f).
template <class T>
T droplet_stokes_number(const T& slip, const T& d_drop, const T& rho_drop, const T& d_p, const T& mu_f,
                        const T& phi_f) {
  return slip * d_drop * d_drop * rho_drop / (18.0 * d_p * mu_f * phi_f);
}

// Paper 000, section 5.1.4: mean Reynolds number Re_m = |u_f - u_p| (1 - phi_p) rho_f d_p / (mu_f phi_f).
template <class T>
T mean_reynolds_number(const T& slip, const T& phi_p, const T& rho_f, const T& d_p, const T& mu_f, const T& phi_f) {
  return slip * (1.0 - phi_p) * rho_f * d_p / (mu_f * phi_f);
}

// Paper 000, section 5.1.4: St*_eff = [A(phi_p) + 1.14 Re_m^(1/5) (1 - phi_p)^(-3/2)] St / 2.
template <class T>
T effective_stokes_number(const T& st, const T& re_m, const T& phi_p) {
  using std::pow;
  return (happel_factor(phi_p) + 1.14 * pow(re_m, 0.2) * pow(1.0 - phi_p, -1.5)) * st / 2.0;
}

// Paper 000, section 5.1.4: single-collector efficiency eta_s = St*^3.2 / (4.3 + St*^3.2), between 0 and 1.
template <class T>
T single_collector_efficiency(const T& st_eff) {
  using std::pow;
  const T s = pow(st_eff, 3.2);
  return s / (4.3 + s);
}

// Paper 000, section 5.1.4: filtration coefficient lambda = eta_s (3 / 2) phi_p / D_p, 1/m.
template <class T>
T filtration_coefficient(const T& eta_s, const T& phi_p, const T& d_p) {
  return eta_s * 1.5 * phi_p / d_p;
}

// Paper 000, section 5.1.4: droplet deposition rate S_d = -lambda |u_d - u_p| mu_liq phi_f rho_f, kg/(m^3 s), with
// mu_liq the droplets' mass loading of the air (kg droplets per kg air); negative: the droplets' sink.
template <class T>
T deposition_rate(const T& lambda, const T& slip, const T& loading, const T& phi_f, const T& rho_f) {
  return -lambda * slip * loading * phi_f * rho_f;
}

// Fraction of the droplets filtered over a path of length L through the bed, 1 - exp(-lambda L): the spray filtration
// integrated along the droplets' path at a constant slip (the clean-bed filter's exponential penetration).
template <class T>
T filtered_fraction(const T& lambda, const T& length) {
  using std::expm1;
  return -expm1(-lambda * length);
}

}  // namespace granuflow::kernels::filtration
