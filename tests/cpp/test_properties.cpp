// Properties of water, vapour, dry and humid air (granuflow/properties.hpp) against hand-computed values,
// Antoine against IAPWS, and one AD derivative against a central finite difference.
#include <gtest/gtest.h>

#include <cmath>

#include "granuflow/ad.hpp"
#include "granuflow/properties.hpp"

namespace granuflow::props {
namespace {

constexpr double kP = 101325.0;
constexpr double kT20 = 293.15;
constexpr double kT60 = 333.15;
constexpr double kT100 = 373.15;

double rel(double x, double ref) { return std::fabs(x - ref) / std::fabs(ref); }

TEST(Properties, AntoineMatchesHandValue) {
  // Eq. (69): ln(p/kPa) = 16.262 - 3800 / (226.3 + 60) = 16.262 - 13.272791 = 2.989209 -> 19.86996 kPa
  EXPECT_NEAR(saturation_pressure(kT60), 19869.96, 0.02);
}

TEST(Properties, AntoineAgreesWithIapws) {
  // IAPWS-95 saturation pressures: 2.339, 19.946, 101.418 kPa at 20, 60, 100 degC.
  EXPECT_LT(rel(saturation_pressure(kT60), 19946.0), 0.01);    // -0.38 %
  EXPECT_LT(rel(saturation_pressure(kT100), 101418.0), 0.01);  // -0.30 %
  // Paper 001's coefficients give 2.3017 kPa at 20 degC, 1.59 % low: the fit, not the code. Pin that figure so
  // a change of coefficients shows up here.
  EXPECT_NEAR(rel(saturation_pressure(kT20), 2339.0), 0.0159, 0.0005);
}

TEST(Properties, LatentHeatIsConsistentWithEnthalpies) {
  EXPECT_DOUBLE_EQ(latent_heat(kT0), 2.501e6);
  // 2.501e6 + (1870 - 4180) * 100 = 2.270e6 J/kg at 100 degC (IAPWS: 2.257e6, constant cp costs 0.6 %)
  EXPECT_NEAR(latent_heat(kT100), 2.270e6, 1e-6);
  // h_v(60 degC) - h_l(10 degC) = 1870*60 + 2.501e6 - 4180*10 = 2.5714e6 = cp_v*50 + latent_heat(10 degC)
  const double dh = vapour_enthalpy(kT60) - liquid_water_enthalpy(283.15);
  EXPECT_NEAR(dh, 2.5714e6, 1e-6);
  EXPECT_NEAR(dh, kCpVapour * 50.0 + latent_heat(283.15), 1e-6);
}

TEST(Properties, HumidityConversionsRoundTrip) {
  // Mw/Mg = 0.01801528 / 0.0289647 = 0.6219736; y = 0.005 / (0.005 + 0.6219736) = 0.00797482
  const double y = mole_fraction_from_humidity(0.005);
  EXPECT_NEAR(y, 0.00797482, 1e-8);
  EXPECT_NEAR(humidity_from_mole_fraction(y), 0.005, 1e-15);
  // p_v = y P = 0.00797482 * 101325 = 808.048 Pa
  const double pv = vapour_partial_pressure(0.005, kP);
  EXPECT_NEAR(pv, 808.048, 1e-3);
  EXPECT_NEAR(humidity_from_partial_pressure(pv, kP), 0.005, 1e-15);
}

TEST(Properties, EquilibriumHumidityAndRelativeHumidity) {
  // Eq. (68): 0.6219736 * 19869.96 / (101325 - 19869.96) = 0.6219736 * 0.2439385 = 0.151723
  EXPECT_NEAR(equilibrium_humidity(kT60, kP), 0.151723, 1e-6);
  // Eq. (82): 808.048 / 2301.729 = 0.351061
  EXPECT_NEAR(relative_humidity(0.005, kT20, kP), 0.351061, 1e-6);
  // saturated gas has relative humidity 1
  EXPECT_NEAR(relative_humidity(equilibrium_humidity(kT60, kP), kT60, kP), 1.0, 1e-14);
}

TEST(Properties, HumidAirEnthalpyAndInverse) {
  // 1006*60 + 0.005*(1870*60 + 2.501e6) = 60360 + 13066 = 73426 J/kg dry air
  EXPECT_NEAR(humid_air_enthalpy(kT60, 0.005), 73426.0, 1e-9);
  EXPECT_NEAR(humid_air_temperature(73426.0, 0.005), kT60, 1e-12);
  EXPECT_DOUBLE_EQ(humid_heat_capacity(0.01), 1006.0 + 18.7);
}

TEST(Properties, Densities) {
  // 101325 * 0.0289647 / (8.314462618 * 333.15) = 2934.8482 / 2769.9632 = 1.0595261 kg/m^3
  EXPECT_NEAR(dry_air_density(kT60, kP), 1.0595261, 1e-7);
  // (101325 - 808.048) * 0.0289647 / 2769.9632 = 1.0510765; times (1 + 0.005) = 1.0563319
  EXPECT_NEAR(dry_air_partial_density(kT60, kP, 0.005), 1.0510765, 1e-7);
  EXPECT_NEAR(humid_air_density(kT60, kP, 0.005), 1.0563319, 1e-7);
}

TEST(Properties, SutherlandAndDimensionlessGroups) {
  EXPECT_DOUBLE_EQ(air_viscosity(273.15), 1.716e-5);
  // 1.716e-5 * (333.15/273.15)^1.5 * 383.55/443.55 = 1.716e-5 * 1.3469700 * 0.8647278 = 1.998732e-5 Pa s
  const double mu = air_viscosity(kT60);
  EXPECT_NEAR(mu, 1.998732e-5, 1e-11);
  // nu = 1.998732e-5 / 1.0595261 = 1.886440e-5 m^2/s
  EXPECT_NEAR(kinematic_viscosity(mu, dry_air_density(kT60, kP)), 1.886440e-5, 1e-11);
  // Eq. (89): 1006 * 1.998732e-5 / 0.024 = 0.837802
  EXPECT_NEAR(prandtl_number(1006.0, mu, 0.024), 0.837802, 1e-6);
  // Eq. (78): 1.998732e-5 / (1.0595261 * 2e-5) = 0.943220
  EXPECT_NEAR(schmidt_number(mu, dry_air_density(kT60, kP), 2e-5), 0.943220, 1e-6);
}

TEST(Properties, JetDerivativesMatchFiniteDifferences) {
  const auto dpsat = [](auto t) { return saturation_pressure(t); };
  const auto drho = [](auto y) { return humid_air_density(decltype(y)(kT60), decltype(y)(kP), y); };
  const auto dmu = [](auto t) { return air_viscosity(t); };
  const Jet t(kT60, 0);
  EXPECT_NEAR(dpsat(t).a, saturation_pressure(kT60), 1e-9);
  const double fd_psat = (dpsat(kT60 + 1e-3) - dpsat(kT60 - 1e-3)) / 2e-3;
  EXPECT_LT(rel(dpsat(t).v[0], fd_psat), 1e-7);
  const double fd_mu = (dmu(kT60 + 1e-3) - dmu(kT60 - 1e-3)) / 2e-3;
  EXPECT_LT(rel(dmu(t).v[0], fd_mu), 1e-7);
  const Jet y(0.01, 3);  // derivative slot 3: the others must stay zero
  const double fd_rho = (drho(0.01 + 1e-6) - drho(0.01 - 1e-6)) / 2e-6;
  EXPECT_LT(rel(drho(y).v[3], fd_rho), 1e-7);
  EXPECT_EQ(drho(y).v[0], 0.0);
}

}  // namespace
}  // namespace granuflow::props
