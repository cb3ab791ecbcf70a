// Physical properties of liquid water, water vapour, dry air and humid air (ideal-gas mixture of the two).
//
// Every function is a template on the scalar type T (double or ceres::Jet) so unit residuals stay exact under
// forward AD; property parameters that calibration might move (Antoine coefficients, heat capacities) are T
// arguments with defaults, true physical constants are plain doubles. SI inside: K, Pa, kg, m, s, J.
// Enthalpy reference: liquid water and dry air at T0 = 273.15 K (0 degC) have zero enthalpy; vapour at T0 has
// the latent heat kLatentHeat0 (docs/paper001_decisions.md "missing gas properties").
// Humidity Y is kg water vapour per kg dry air throughout.
#pragma once
#include <cmath>

namespace granuflow::props {

// --- constants (unit in the comment; source in brackets) ---
inline constexpr double kT0 = 273.15;                  // K, enthalpy reference and degC offset
inline constexpr double kGasConstant = 8.314462618;    // J/(mol K) [CODATA 2018]
inline constexpr double kGravity = 9.80665;            // m/s^2 [standard gravity]
inline constexpr double kPressureAtm = 101325.0;       // Pa, operating pressure [docs/paper001_decisions.md]
inline constexpr double kMolarMassWater = 0.01801528;  // kg/mol
inline constexpr double kMolarMassAir = 0.0289647;     // kg/mol, dry air
inline constexpr double kCpAir = 1006.0;               // J/(kg K), dry air [docs/paper001_decisions.md]
inline constexpr double kCpVapour = 1870.0;            // J/(kg K), water vapour [docs/paper001_decisions.md]
inline constexpr double kCpWater = 4180.0;             // J/(kg K), liquid water [docs/paper001_decisions.md, Table 6]
inline constexpr double kLatentHeat0 = 2.501e6;        // J/kg, evaporation of water at T0 [docs/paper001_decisions.md]
inline constexpr double kAntoineA = 16.262;            // -, ln(p/kPa) form [paper 001, Table 8]
inline constexpr double kAntoineB = 3800.0;            // degC (K difference) [paper 001, Table 8]
inline constexpr double kAntoineC = 226.3;             // degC [paper 001, Table 8]
inline constexpr double kSutherlandMuRef = 1.716e-5;   // Pa s, air at kSutherlandTRef [White, Viscous Fluid Flow]
inline constexpr double kSutherlandTRef = 273.15;      // K
inline constexpr double kSutherlandS = 110.4;          // K, Sutherland constant of air

// --- water ---

// Eq. (69), paper 001: Antoine, p in kPa, T in degC. With the paper's coefficients the fit is 1.6 % low at
// 20 degC and within 0.4 % of IAPWS from 60 to 100 degC.
template <class T>
T saturation_pressure(const T& temp, const T& a = T(kAntoineA), const T& b = T(kAntoineB), const T& c = T(kAntoineC)) {
  using std::exp;
  return 1000.0 * exp(a - b / (c + (temp - kT0)));
}

// Latent heat at `temp` consistent with the constant heat capacities (Kirchhoff): then
// h_vapour(T_gas) - h_liquid(T_liq) = cp_v (T_gas - T_liq) + latent_heat(T_liq) holds exactly, so energy
// balances written with Eqs. (63), (67), (71) close.
template <class T>
T latent_heat(const T& temp, const T& dh0 = T(kLatentHeat0), const T& cp_v = T(kCpVapour),
              const T& cp_l = T(kCpWater)) {
  return dh0 + (cp_v - cp_l) * (temp - kT0);
}

template <class T>
T liquid_water_enthalpy(const T& temp, const T& cp_l = T(kCpWater)) {
  return cp_l * (temp - kT0);
}

template <class T>
T vapour_enthalpy(const T& temp, const T& cp_v = T(kCpVapour), const T& dh0 = T(kLatentHeat0)) {
  return cp_v * (temp - kT0) + dh0;
}

// --- humidity conversions (ideal-gas mixture of water vapour and dry air) ---

// Vapour mole fraction y from humidity Y.
template <class T>
T mole_fraction_from_humidity(const T& y_abs) {
  return y_abs / (y_abs + kMolarMassWater / kMolarMassAir);
}

template <class T>
T humidity_from_mole_fraction(const T& y) {
  return (kMolarMassWater / kMolarMassAir) * y / (1.0 - y);
}

// Eq. (83), paper 001: Dalton, p_v = y P.
template <class T>
T vapour_partial_pressure(const T& y_abs, const T& p) {
  return mole_fraction_from_humidity(y_abs) * p;
}

// Humidity of a gas at total pressure p holding vapour at partial pressure p_v; Eq. (68) is its value at
// saturation.
template <class T>
T humidity_from_partial_pressure(const T& p_v, const T& p) {
  return (kMolarMassWater / kMolarMassAir) * p_v / (p - p_v);
}

// Eq. (68), paper 001: equilibrium (saturation) humidity over free water at `temp`.
template <class T>
T equilibrium_humidity(const T& temp, const T& p) {
  return humidity_from_partial_pressure(saturation_pressure(temp), p);
}

// Eq. (82), paper 001: relative humidity = water activity of a solid in equilibrium with the gas, evaluated
// with p_sat at `temp` (the solids temperature in the drying model, docs/paper001_decisions.md).
template <class T>
T relative_humidity(const T& y_abs, const T& temp, const T& p) {
  return vapour_partial_pressure(y_abs, p) / saturation_pressure(temp);
}

// --- humid air (per kg dry air) ---

// Humid heat: J per kg dry air per K.
template <class T>
T humid_heat_capacity(const T& y_abs, const T& cp_g = T(kCpAir), const T& cp_v = T(kCpVapour)) {
  return cp_g + y_abs * cp_v;
}

// Consistent with Eq. (63), paper 001, with temperatures measured from T0: J per kg dry air.
template <class T>
T humid_air_enthalpy(const T& temp, const T& y_abs, const T& cp_g = T(kCpAir), const T& cp_v = T(kCpVapour),
                     const T& dh0 = T(kLatentHeat0)) {
  return cp_g * (temp - kT0) + y_abs * (cp_v * (temp - kT0) + dh0);
}

// Inverse of humid_air_enthalpy in temperature, so a unit may carry enthalpy as its state.
template <class T>
T humid_air_temperature(const T& h, const T& y_abs, const T& cp_g = T(kCpAir), const T& cp_v = T(kCpVapour),
                        const T& dh0 = T(kLatentHeat0)) {
  return kT0 + (h - y_abs * dh0) / (cp_g + y_abs * cp_v);
}

// Ideal-gas density of dry air, kg/m^3.
template <class T>
T dry_air_density(const T& temp, const T& p) {
  return p * kMolarMassAir / (kGasConstant * temp);
}

// Mass of dry air per m^3 of humid air: the density that pairs with a humidity difference in a mass flux
// (Eq. (72)) because Y is per kg dry air.
template <class T>
T dry_air_partial_density(const T& temp, const T& p, const T& y_abs) {
  return dry_air_density(temp, T(p - vapour_partial_pressure(y_abs, p)));
}

// Ideal-gas density of humid air (dry air plus vapour), kg/m^3.
template <class T>
T humid_air_density(const T& temp, const T& p, const T& y_abs) {
  return (1.0 + y_abs) * dry_air_partial_density(temp, p, y_abs);
}

// Sutherland's law for air, Pa s; the vapour's effect on viscosity is below 1 % at these humidities.
template <class T>
T air_viscosity(const T& temp) {
  using std::pow;
  return kSutherlandMuRef * pow(temp / kSutherlandTRef, 1.5) * (kSutherlandTRef + kSutherlandS) / (temp + kSutherlandS);
}

// Kinematic viscosity, m^2/s.
template <class T>
T kinematic_viscosity(const T& mu, const T& rho) {
  return mu / rho;
}

// Eq. (89), paper 001.
template <class T>
T prandtl_number(const T& cp, const T& mu, const T& lambda) {
  return cp * mu / lambda;
}

// Eq. (78), paper 001.
template <class T>
T schmidt_number(const T& mu, const T& rho, const T& diffusivity) {
  return mu / (rho * diffusivity);
}

}  // namespace granuflow::props
