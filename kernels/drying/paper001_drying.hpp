// Particle drying, droplet evaporation and the attached enthalpy flows of paper 001 (Eqs. (65)-(83)):
// Burgschweiger-Tsotsas drying with a linear normalized drying curve and a BET sorption isotherm.
//
// Templates on the scalar type T (double or ceres::Jet); SI units; moisture X in kg water per kg dry solid;
// humidity Y in kg water per kg dry air. Mass-transfer coefficients come from transfer/fluid_bed_transfer.hpp,
// saturation pressure and humidity conversions from granuflow/properties.hpp.
#pragma once
#include "granuflow/properties.hpp"
#include "limited.hpp"
#include "paper001_defaults.hpp"

namespace granuflow::kernels::paper001 {

// Eq. (81), paper 001: BET isotherm, m_m in kg/kg dry basis at all temperatures (docs/paper001_decisions.md).
// Singular at a = 1: a gas saturated at the solids temperature has no finite equilibrium moisture, so a unit
// that can reach it caps a first (cap_at in limited.hpp) and counts it.
template <class T>
T bet_equilibrium_moisture(const T& a, const T& m_m = T(defaults::kBetMonolayer), const T& n = T(defaults::kBetN)) {
  return m_m * n * a / ((1.0 - a) * (1.0 + (n - 1.0) * a));
}

// Eqs. (82)-(83), paper 001: a = y P / p_sat(T_S), y the vapour mole fraction of the bulk gas and p_sat at the
// solids temperature (docs/paper001_decisions.md).
template <class T>
T water_activity(const T& y_abs_bulk, const T& t_solid, const T& p) {
  return props::relative_humidity(y_abs_bulk, t_solid, p);
}

// Eq. (80), paper 001, regularized (docs/paper001_decisions.md): the denominator X_cr - X_eq is floored (the literal
// eta flips sign and diverges when a humid gas lifts X_eq to X_cr) and eta >= eta_min limits re-adsorption
// when X < X_eq. `active` reports either.
template <class T>
Limited<T> normalized_moisture(const T& x, const T& x_eq, const T& x_cr,
                               const T& denominator_floor = T(defaults::kEtaDenominatorFloor),
                               const T& eta_min = T(defaults::kEtaMin)) {
  const Limited<T> den = floor_at(T(x_cr - x_eq), denominator_floor);
  const Limited<T> eta = floor_at(T((x - x_eq) / den.value), eta_min);
  return {eta.value, den.active || eta.active};
}

// Eq. (68), paper 001, with the saturation pressure capped at `cap` p: Eq. (68) diverges as p_sat approaches
// the total pressure (water boiling at the surface, e.g. a bed or gas at 100 degC), where the surface flux is
// limited by heat supply instead. `active` reports the cap (a regularization beyond the paper).
template <class T>
Limited<T> saturation_humidity(const T& temp, const T& p, double cap = 0.9) {
  const Limited<T> ps = cap_at(props::saturation_pressure(temp), T(cap * p));
  return {props::humidity_from_partial_pressure(ps.value, p), ps.active};
}

// Eq. (79), paper 001: linear drying curve, full rate above the critical moisture.
template <class T>
T linear_drying_curve(const T& eta) {
  return eta < 1.0 ? eta : T(1.0);
}

// Eq. (72), paper 001: kg/(m^2 s). With Y per kg dry air, rho_g is best the dry-air partial density
// (props::dry_air_partial_density); Y_eq at the solids temperature (docs/paper001_decisions.md).
template <class T>
T drying_mass_flux(const T& rho_g, const T& k_drying, const T& y_eq, const T& y_bulk) {
  return rho_g * k_drying * (y_eq - y_bulk);
}

// Eq. (70), paper 001: kg/s from a class of total surface `area` (N_i pi d_i^2, docs/paper001_decisions.md).
template <class T>
T drying_rate(const T& nu, const T& area, const T& j) {
  return nu * area * j;
}

// Droplet surface produced per second by spraying `m_liquid` kg/s as droplets of diameter d_d: m^2/s, the A_drop
// of Eq. (66) (docs/paper001_decisions.md).
template <class T>
T droplet_surface_rate(const T& m_liquid, const T& rho_l, const T& d_d) {
  return 6.0 * m_liquid / (rho_l * d_d);
}

// Eq. (66), paper 001: kg/s; k_evap in kg/m^2 per unit Delta Y because A_drop is m^2/s; Y_eq at the gas
// temperature (docs/paper001_decisions.md).
template <class T>
T droplet_evaporation_rate(const T& k_evap, const T& a_drop, const T& y_eq, const T& y_bulk) {
  return k_evap * a_drop * (y_eq - y_bulk);
}

// Eq. (65), paper 001: W; the paper's cp T with T measured from the 0 degC reference of props.
template <class T>
T deposition_enthalpy_flow(const T& m_deposition, const T& t_spray, const T& cp_l = T(props::kCpWater)) {
  return m_deposition * props::liquid_water_enthalpy(t_spray, cp_l);
}

// Common form of Eqs. (67) and (71), paper 001: W needed to turn m kg/s of liquid at t_liquid into vapour at
// t_gas. With cp_i = cp_vapour and the latent heat taken at t_liquid this equals m (h_vapour(t_gas) -
// h_liquid(t_liquid)) exactly, so the balances close. It is drawn from the gas (docs/paper001_decisions.md on the sign
// of Eqs. (62), (67)).
template <class T>
T phase_change_enthalpy_flow(const T& m, const T& t_gas, const T& t_liquid, const T& cp_v = T(props::kCpVapour),
                             const T& cp_l = T(props::kCpWater), const T& dh0 = T(props::kLatentHeat0)) {
  return m * (cp_v * (t_gas - t_liquid) + props::latent_heat(t_liquid, dh0, cp_v, cp_l));
}

// Eq. (67), paper 001: droplet evaporation, liquid at the spray temperature.
template <class T>
T evaporation_enthalpy_flow(const T& m_evap, const T& t_gas, const T& t_spray) {
  return phase_change_enthalpy_flow(m_evap, t_gas, t_spray);
}

// Eq. (71), paper 001: particle drying, liquid at the solids temperature.
template <class T>
T drying_enthalpy_flow(const T& m_drying, const T& t_gas, const T& t_solid) {
  return phase_change_enthalpy_flow(m_drying, t_gas, t_solid);
}

}  // namespace granuflow::kernels::paper001
