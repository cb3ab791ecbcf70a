// The Stokes numbers of a wet collision (paper 003, Eqs. (7.57)-(7.58); paper 000, section 5.6): whether liquid
// dissipates a collision's energy (coalescence) and whether a granule deforms. Templates on the scalar type; SI units.
#pragma once
#include <cmath>

#include "particle_geometry.hpp"

namespace granuflow::kernels::stokes {

// Paper 003, Eq. (7.57): viscous Stokes number St = 2 M u / (3 pi mu_l d^2) of a collision of mass M and diameter d.
template <class T>
T viscous_stokes_number(const T& mass, const T& u_coll, const T& mu_l, const T& d) {
  return 2.0 * mass * u_coll / (3.0 * kPi * mu_l * d * d);
}

// Paper 003, Eq. (7.58): critical Stokes number of coalescence St*_coal = (1 + 1/e) ln(h / h_a).
template <class T>
T critical_coalescence(const T& e, const T& h, const T& h_a) {
  using std::log;
  return (1.0 + 1.0 / e) * log(h / h_a);
}

// Paper 000, section 5.6: critical Stokes deformation number St*_def = 2 St*_coal = 2 (1 + 1/e) ln(h / h_a); drying
// lowers h (and raises mu_l), and a granule deforms (breaks) when its Stokes deformation number exceeds it.
template <class T>
T critical_deformation(const T& e, const T& h, const T& h_a) {
  return 2.0 * critical_coalescence(e, h, h_a);
}

}  // namespace granuflow::kernels::stokes
