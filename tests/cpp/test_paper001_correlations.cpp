// Closures of paper 001 (transfer, drying, spray zone, breakage) against hand-computed values, the reporting of
// every floor / cap / regularization, and AD derivatives (ceres::Jet) against central finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "granuflow/ad.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/properties.hpp"
#include "kernels/breakage/paper001_breakage_laws.hpp"
#include "kernels/drying/paper001_drying.hpp"
#include "kernels/paper001_defaults.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/paper001_spray_zone.hpp"

namespace granuflow::kernels {
namespace {

using namespace paper001;  // NOLINT: the functions under test
using namespace transfer;  // NOLINT

constexpr double kP = 101325.0;
constexpr double kT60 = 333.15;

double rel(double x, double ref) { return std::fabs(x - ref) / std::fabs(ref); }

// dF/dx from one Jet evaluation (slot `slot` seeded) against a central difference with step h.
template <class F>
void expect_jet_matches_fd(F f, double x, double h, double tol, int slot = 0) {
  const Jet y = f(Jet(x, slot));
  EXPECT_NEAR(y.a, f(x), 1e-12 * std::fabs(f(x)) + 1e-300);
  const double fd = (f(x + h) - f(x - h)) / (2.0 * h);
  EXPECT_LT(rel(y.v[slot], fd), tol) << "x = " << x << ", jet " << y.v[slot] << ", fd " << fd;
  for (int k = 0; k < kAdChunk; ++k) {
    if (k != slot) {
      EXPECT_EQ(y.v[k], 0.0);
    }
  }
}

// ---------------------------------------------------------------- transfer

TEST(Paper001Transfer, WenYuMinimumFluidization) {
  // Air at 60 degC: rho_g = 1.0595261 kg/m^3, mu = 1.998732e-5 Pa s (test_properties); d = 200 um,
  // rho_p = 1081.5 kg/m^3. Eq. (33): Ar = 1.0595261 * 8e-12 * 1080.4405 * 9.80665 / 3.994930e-10 = 224.8091
  const double rho = props::dry_air_density(kT60, kP);
  const double mu = props::air_viscosity(kT60);
  const double ar = archimedes_number(200e-6, 1081.5, rho, mu);
  EXPECT_NEAR(ar, 224.8091, 1e-4);
  // Eq. (32): (-1650 + sqrt(1650^2 + 98 * 224.8091)) / 49 = (-1650 + 1656.662698) / 49 = 0.1359734
  const double re_mf = wen_yu_reynolds_mf(ar);
  EXPECT_NEAR(re_mf, 0.1359734, 1e-7);
  // Eq. (31): 0.1359734 * 1.886440e-5 / 2e-4 = 0.01282528 m/s
  EXPECT_NEAR(minimum_fluidization_velocity(re_mf, mu / rho, 200e-6), 0.01282528, 1e-8);
  EXPECT_NEAR(wen_yu_umf(200e-6, 1081.5, rho, mu), 0.01282528, 1e-8);
  // the rationalized root is the printed one: 24.5 Re^2 + 1650 Re = Ar at a large Ar too
  const double re_big = wen_yu_reynolds_mf(1e6);
  EXPECT_NEAR(24.5 * re_big * re_big + 1650.0 * re_big, 1e6, 1e-6);
  EXPECT_NEAR(re_big, (-1650.0 + std::sqrt(1650.0 * 1650.0 + 98.0 * 1e6)) / 49.0, 1e-10);
}

TEST(Paper001Transfer, ReynoldsNumbersAndVelocity) {
  // Eq. (77): 700 m^3/h / 0.25 m^2 = 0.1944444 / 0.25 = 0.7777778 m/s
  const double u0 = superficial_velocity(700.0 / 3600.0, defaults::kBedArea);
  EXPECT_NEAR(u0, 0.7777778, 1e-7);
  // Eq. (30): (0.7777778 - 0.01282528) * 2e-4 / 1.886440e-5 = 8.110012
  EXPECT_NEAR(excess_reynolds_number(u0, 0.01282528, 2e-4, 1.886440e-5), 8.110012, 1e-5);
  // Eq. (76): 0.7777778 * 2e-4 / 1.886440e-5 = 8.245985
  EXPECT_NEAR(particle_reynolds_number(u0, 2e-4, 1.886440e-5), 8.245985, 1e-5);
}

TEST(Paper001Transfer, RanzMarshall) {
  // Eq. (75): 2 + 0.6 * sqrt(4) * cbrt(0.729) = 2 + 0.6 * 2 * 0.9 = 3.08
  EXPECT_NEAR(sherwood_single(4.0, 0.729), 3.08, 1e-14);
  // Eq. (88): 2 + 0.6 * sqrt(9) * cbrt(0.512) = 2 + 0.6 * 3 * 0.8 = 3.44
  EXPECT_NEAR(nusselt_single(9.0, 0.512), 3.44, 1e-14);
}

TEST(Paper001Transfer, BulkSherwoodAndNusselt) {
  // Eq. (74), eps = 1, A_p/A_inlet = 100: Re Sc = 2.916; 2.916/100 * ln(1 + 3.08*100/2.916)
  //   = 0.02916 * ln(106.6241) = 0.02916 * 4.669309 = 0.1361571
  EXPECT_NEAR(bulk_sherwood(3.08, 4.0, 0.729, 100.0), 0.1361571, 1e-7);
  EXPECT_NEAR(bulk_sherwood(3.08, 4.0, 0.729, 100.0, 0.5), 0.5 * 0.1361571, 1e-7);
  // Eq. (87): Re Pr = 4.608; 4.608/100 * ln(1 + 3.44*100/4.608) = 0.04608 * ln(75.65278) = 0.04608 * 4.326154
  //   = 0.1993492
  EXPECT_NEAR(bulk_nusselt(3.44, 9.0, 0.512, 100.0), 0.1993492, 1e-7);
  // a vanishing particle surface recovers the single-particle value
  EXPECT_NEAR(bulk_nusselt(3.44, 9.0, 0.512, 1e-12), 3.44, 1e-9);
  // A_p/A_inlet: 1e6 particles of 200 um = 1e6 * pi * 4e-8 = 0.1256637 m^2 over 0.25 m^2 = 0.5026548
  EXPECT_NEAR(bed_area_ratio(class_surface(1e6, 2e-4), 0.25), 0.5026548, 1e-7);
}

TEST(Paper001Transfer, TransferCoefficients) {
  // Eq. (73): 2 * 2e-5 / 2e-4 = 0.2 m/s; Eq. (86): 2 * 0.024 / 2e-4 = 240 W/(m^2 K)
  EXPECT_NEAR(mass_transfer_coefficient(2.0, 2e-5, 2e-4), 0.2, 1e-15);
  EXPECT_NEAR(heat_transfer_coefficient(2.0, 0.024, 2e-4), 240.0, 1e-12);
}

// ---------------------------------------------------------------- drying

TEST(Paper001Drying, BetIsotherm) {
  // Eq. (81), a = 0.3: 0.037 * 11.9 * 0.3 / (0.7 * (1 + 10.9 * 0.3)) = 0.13209 / (0.7 * 4.27) = 0.13209 / 2.989
  //   = 0.04419204
  EXPECT_NEAR(bet_equilibrium_moisture(0.3), 0.04419204, 1e-8);
  EXPECT_EQ(bet_equilibrium_moisture(0.0), 0.0);
}

TEST(Paper001Drying, WaterActivity) {
  // Eqs. (82)-(83): Y = 0.005 -> p_v = 808.048 Pa; p_sat(20 degC) = 2301.729 Pa; a = 0.351061
  EXPECT_NEAR(water_activity(0.005, 293.15, kP), 0.351061, 1e-6);
}

TEST(Paper001Drying, NormalizedMoistureAndItsRegularization) {
  // Eq. (80) literal: (0.05 - 0.01) / (0.07 - 0.01) = 0.6666667
  auto eta = normalized_moisture(0.05, 0.01, 0.07);
  EXPECT_NEAR(eta.value, 2.0 / 3.0, 1e-15);
  EXPECT_FALSE(eta.active);
  // re-adsorption within the limit: (0.005 - 0.03) / (0.07 - 0.03) = -0.625, literal
  eta = normalized_moisture(0.005, 0.03, 0.07);
  EXPECT_NEAR(eta.value, -0.625, 1e-15);
  EXPECT_FALSE(eta.active);
  // X_eq near X_cr: denominator 0.005 -> 0.01; (0.08 - 0.065) / 0.01 = 1.5
  eta = normalized_moisture(0.08, 0.065, 0.07);
  EXPECT_NEAR(eta.value, 1.5, 1e-13);
  EXPECT_TRUE(eta.active);
  // strong re-adsorption: (0 - 0.05) / 0.02 = -2.5 -> -1
  eta = normalized_moisture(0.0, 0.05, 0.07);
  EXPECT_EQ(eta.value, -1.0);
  EXPECT_TRUE(eta.active);
  // Eq. (79)
  EXPECT_EQ(linear_drying_curve(0.6), 0.6);
  EXPECT_EQ(linear_drying_curve(1.5), 1.0);
}

TEST(Paper001Drying, DryingFluxAndRate) {
  // Eq. (72): 1.05 * 0.2 * (0.02 - 0.01) = 2.1e-3 kg/(m^2 s); Eq. (70): 0.5 * 10 m^2 * 2.1e-3 = 1.05e-2 kg/s
  const double j = drying_mass_flux(1.05, 0.2, 0.02, 0.01);
  EXPECT_NEAR(j, 2.1e-3, 1e-17);
  EXPECT_NEAR(drying_rate(0.5, 10.0, j), 1.05e-2, 1e-16);
}

TEST(Paper001Drying, DropletEvaporation) {
  // 90 g/min = 1.5e-3 kg/s as 30 um droplets: A = 6 * 1.5e-3 / (1000 * 30e-6) = 0.3 m^2/s
  const double a = droplet_surface_rate(1.5e-3, 1000.0, 30e-6);
  EXPECT_NEAR(a, 0.3, 1e-15);
  // Eq. (66): 3e-3 * 0.3 * (0.15 - 0.005) = 1.305e-4 kg/s
  EXPECT_NEAR(droplet_evaporation_rate(3e-3, a, 0.15, 0.005), 1.305e-4, 1e-18);
}

TEST(Paper001Drying, EnthalpyFlows) {
  // Eq. (65): 1e-3 kg/s * 4180 * (283.15 - 273.15) = 41.8 W
  EXPECT_NEAR(deposition_enthalpy_flow(1e-3, 283.15), 41.8, 1e-12);
  // Eq. (67): 1e-4 * (1870 * 50 + 2.501e6 - 2310 * 10) = 1e-4 * (93500 + 2477900) = 257.14 W
  EXPECT_NEAR(evaporation_enthalpy_flow(1e-4, kT60, 283.15), 257.14, 1e-9);
  // Eq. (71): 1e-4 * (1870 * 20 + 2.501e6 - 2310 * 40) = 1e-4 * (37400 + 2408600) = 244.6 W
  EXPECT_NEAR(drying_enthalpy_flow(1e-4, kT60, 313.15), 244.6, 1e-9);
  // closes with the state enthalpies of props
  EXPECT_NEAR(drying_enthalpy_flow(1e-4, kT60, 313.15),
              1e-4 * (props::vapour_enthalpy(kT60) - props::liquid_water_enthalpy(313.15)), 1e-9);
}

// ---------------------------------------------------------------- spray zone

TEST(Paper001SprayZone, ResidenceTimeAndNormalization) {
  // Eq. (29): -3e-3 * 10 + 0.23 = 0.2
  EXPECT_NEAR(dimensionless_residence_time(10.0), 0.2, 1e-15);
  // Eq. (34): {0.2, 0.1, 0.1} / 0.4
  const std::vector<double> tau{0.2, 0.1, 0.1};
  std::vector<double> out(3);
  normalize_residence_times(tau.data(), tau.size(), out.data());
  EXPECT_NEAR(out[0], 0.5, 1e-15);
  EXPECT_NEAR(out[1], 0.25, 1e-15);
  EXPECT_NEAR(out[2], 0.25, 1e-15);
}

TEST(Paper001SprayZone, LiquidDistributionBothReadings) {
  const std::vector<double> tau{0.2, 0.1}, d{1e-4, 2e-4}, n{100.0, 10.0};
  std::vector<double> m(2);
  // literal Eq. (35): weights 0.2 * 1e-8 = 2e-9 and 0.1 * 4e-8 = 4e-9 -> 1/3, 2/3 of 3 kg/s
  distribute_liquid(tau.data(), d.data(), n.data(), 2, 3.0, LiquidSplit::kLiteral, m.data());
  EXPECT_NEAR(m[0], 1.0, 1e-14);
  EXPECT_NEAR(m[1], 2.0, 1e-14);
  // class surface: weights 100 * 2e-9 = 2e-7 and 10 * 4e-9 = 4e-8 -> 5/6, 1/6 of 3 kg/s
  distribute_liquid(tau.data(), d.data(), n.data(), 2, 3.0, LiquidSplit::kClassSurface, m.data());
  EXPECT_NEAR(m[0], 2.5, 1e-14);
  EXPECT_NEAR(m[1], 0.5, 1e-14);
  // literal ignores the counts
  distribute_liquid(tau.data(), d.data(), static_cast<const double*>(nullptr), 2, 3.0, LiquidSplit::kLiteral, m.data());
  EXPECT_NEAR(m[0], 1.0, 1e-14);
  EXPECT_EQ(liquid_split_from_string("literal"), LiquidSplit::kLiteral);
  EXPECT_EQ(liquid_split_from_string(to_string(LiquidSplit::kClassSurface)), LiquidSplit::kClassSurface);
  EXPECT_THROW(liquid_split_from_string("surface"), ConfigError);
}

TEST(Paper001SprayZone, SolidsFractionFloor) {
  // Eq. (47), Re = 10: -3e-4 * 100 + 5.5e-3 * 10 + 0.13 = -0.03 + 0.055 + 0.13 = 0.155
  auto w = spray_zone_solids_fraction(10.0);
  EXPECT_NEAR(w.value, 0.155, 1e-15);
  EXPECT_FALSE(w.active);
  // Re = 30: -0.27 + 0.165 + 0.13 = 0.025 < 0.05 -> floored
  w = spray_zone_solids_fraction(30.0);
  EXPECT_EQ(w.value, 0.05);
  EXPECT_TRUE(w.active);
  // the floor is a parameter
  w = spray_zone_solids_fraction(30.0, 0.0);
  EXPECT_NEAR(w.value, 0.025, 1e-15);
  EXPECT_FALSE(w.active);
}

TEST(Paper001SprayZone, VelocityCrossingTimeHoldupAndFlow) {
  // Eq. (49): 1e-2 * 10 + 6.6e-2 = 0.166 m/s; Eq. (48): 0.3 / 0.166 = 1.807229 s
  const double v = spray_zone_particle_velocity(10.0);
  EXPECT_NEAR(v, 0.166, 1e-15);
  const double t = spray_zone_crossing_time(v);
  EXPECT_NEAR(t, 1.807229, 1e-6);
  // Eq. (46): 0.155 * 2 kg = 0.31 kg; Eq. (45): 0.31 / 1.807229 = 0.1715333 kg/s
  const double m = spray_zone_holdup(0.155, 2.0);
  EXPECT_NEAR(m, 0.31, 1e-15);
  EXPECT_NEAR(spray_zone_solids_flow(m, t), 0.1715333, 1e-7);
  // Eq. (43): 1e-3 / 0.1 = 0.01 kg/kg
  EXPECT_NEAR(moisture_loading(1e-3, 0.1), 0.01, 1e-16);
}

TEST(Paper001SprayZone, CoatingNumberAndCoverage) {
  // Eqs. (42), (50), (51): X d^3 rho_env (pi d_d^2/4) / (d_d^3 rho_d pi d^2) = X d rho_env / (4 d_d rho_d)
  //   = 0.01 * 200e-6 * 900 / (4 * 30e-6 * 1000) = 1.8e-3 / 0.12 = 0.015
  const double phi = coating_number(0.01, 200e-6, 30e-6);
  EXPECT_NEAR(phi, 0.015, 1e-15);
  // Eq. (41): 1 - exp(-0.015) = 0.01488806
  EXPECT_NEAR(surface_coverage(phi), 0.01488806, 1e-8);
  EXPECT_NEAR(surface_coverage(std::log(2.0)), 0.5, 1e-15);
  // Eq. (40): 1 - 0.5 * 0.8 = 0.6
  EXPECT_NEAR(geometric_success_factor(0.5, 0.2), 0.6, 1e-15);
  // Eqs. (50), (51)
  EXPECT_NEAR(sphere_cross_section(30e-6), 7.0685835e-10, 1e-16);
  EXPECT_NEAR(sphere_surface(200e-6), 1.2566371e-7, 1e-14);
}

TEST(Paper001SprayZone, WettedVolumeCapExposedFlowWetSpot) {
  // Eq. (57) / V_p: h_pen pi d^2 f / (pi d^3 / 6) = 6 h_pen f / d = 6 * 168e-6 * 0.1 / 200e-6 = 0.504
  auto frac = wetted_volume_fraction(0.1, 200e-6);
  EXPECT_NEAR(frac.value, 0.504, 1e-14);
  EXPECT_FALSE(frac.active);
  // f = 0.5 -> 2.52 > 1: capped at the particle volume
  frac = wetted_volume_fraction(0.5, 200e-6);
  EXPECT_EQ(frac.value, 1.0);
  EXPECT_TRUE(frac.active);
  // as a volume: 168e-6 * pi * 4e-8 * 0.1 = 2.111150e-12 m^3 (V_p = 4.188790e-12), and capped at V_p
  EXPECT_NEAR(wetted_volume(0.1, 200e-6).value, 2.111150e-12, 1e-18);
  EXPECT_NEAR(wetted_volume(0.5, 200e-6).value, 4.188790e-12, 1e-18);
  EXPECT_TRUE(wetted_volume(0.5, 200e-6).active);
  // Eq. (56): 0.1 kg/s * 0.504 = 0.0504; Eq. (55): 1e-3 / 0.0504 + 0.03 = 0.04984127
  const double m_exp = exposed_solids_flow(0.1, 0.504);
  EXPECT_NEAR(m_exp, 0.0504, 1e-16);
  EXPECT_NEAR(wet_spot_moisture(1e-3, m_exp, 0.03), 0.04984127, 1e-8);
}

TEST(Paper001SprayZone, GordonTaylor) {
  // Eq. (54), X = 0.05: x = 0.05/1.05 = 0.04761905; k x = 0.3047619; 1 - x = 0.9523810
  //   (0.3047619 * 138.15 + 0.9523810 * 440.15) / (0.3047619 + 0.9523810) = 461.2933 / 1.257143 = 366.9379 K
  //   (in degC: (0.3047619 * -135 + 0.9523810 * 167) / 1.257143 = 93.7879 degC, the same)
  EXPECT_NEAR(gordon_taylor(0.05), 366.9379, 1e-4);
  EXPECT_NEAR(liquid_mass_fraction(0.05), 0.04761905, 1e-8);
  EXPECT_DOUBLE_EQ(gordon_taylor(0.0), 440.15);
}

TEST(Paper001SprayZone, StickyProbability) {
  const double tg = 366.9379;
  // Eq. (53): 0.5 (tanh(-20/8.733) + 1) = 0.5 (1 - 0.9797050) = 0.0101475 (the paper's "1 %"), 0.5 at
  // Tg + 20 K, 0.9898525 at Tg + 40 K (its "99 %"); the tanh rounds the stated levels by 1.5e-4.
  EXPECT_NEAR(sticky_probability(tg, tg), 0.01, 2e-4);
  EXPECT_NEAR(sticky_probability(tg + 20.0, tg), 0.5, 1e-15);
  EXPECT_NEAR(sticky_probability(tg + 40.0, tg), 0.99, 2e-4);
  EXPECT_NEAR(sticky_probability(tg, tg), 0.01014751, 1e-8);
  // Eq. (52): 1 - 0.7 * 0.5 = 0.65
  EXPECT_NEAR(physical_success_factor(0.3, 0.5), 0.65, 1e-15);
}

TEST(Paper001SprayZone, CollisionFrequencyAndKernel) {
  // Eq. (37), d_i = d_j = 200 um: (4e-4)^2 sqrt(2 / 8e-12) = 1.6e-7 * 5e5 = 0.08; times tau_spray 0.22 = 0.0176
  EXPECT_NEAR(collision_frequency(200e-6, 200e-6, 0.0), 0.0176, 1e-15);
  // with beta0 = exp(-17.24) = 3.256590e-8: 5.731599e-10 1/s
  const double cf = collision_frequency(200e-6, 200e-6);
  EXPECT_NEAR(cf, 5.731599e-10, 1e-16);
  // Eq. (39)
  EXPECT_NEAR(agglomeration_kernel(cf, 0.6, 0.65), cf * 0.39, 1e-24);
  // symmetric in the partners
  EXPECT_DOUBLE_EQ(collision_frequency(100e-6, 400e-6), collision_frequency(400e-6, 100e-6));
}

// ---------------------------------------------------------------- breakage

TEST(Paper001Breakage, VogelPeukertRate) {
  // Eq. (91): 100 um -> 0.3 * 100 / 50 = 0.6 J/kg
  EXPECT_NEAR(impact_energy(100.0, 0.3, 50.0), 0.6, 1e-15);
  // Eq. (92), um: 60 um -> 0.3 * 60 * (60/50 - 1) = 3.6; 1.3e-3 * (1 - exp(-3.6)) = 1.264479e-3 1/s
  EXPECT_NEAR(breakage_rate(60e-6), 1.264479e-3, 1e-9);
  // 200 um -> exponent 180: k' itself
  EXPECT_NEAR(breakage_rate(200e-6), 1.3e-3, 1e-15);
  // at and below d_min,break the threshold is not reached: no breakage (not a negative rate)
  EXPECT_EQ(breakage_rate(50e-6), 0.0);
  EXPECT_EQ(breakage_rate(30e-6), 0.0);
  // mm option: 0.2 mm -> 0.3 * 0.2 * (0.2/0.05 - 1) = 0.18; 1.3e-3 * (1 - exp(-0.18)) = 2.141487e-4 1/s
  EXPECT_NEAR(breakage_rate(200e-6, BreakageSizeUnit::kMillimetre), 2.141487e-4, 1e-10);
  EXPECT_EQ(breakage_size_unit_from_string("mm"), BreakageSizeUnit::kMillimetre);
  EXPECT_EQ(to_string(BreakageSizeUnit::kMicrometre), "um");
  EXPECT_THROW(breakage_size_unit_from_string("cm"), ConfigError);
}

TEST(Paper001Breakage, CumulativeFragmentDistribution) {
  // Eq. (93), fragment 100 um of a 400 um parent, q = 0.5, d_min = 50 um:
  //   (1/4)^0.5 * 0.5 (1 + tanh(1)) / (0.5 (1 + tanh(7))) = 0.5 * 0.8807971 / 0.9999992 = 0.4403989
  EXPECT_NEAR(cumulative_fragment_distribution(100e-6, 400e-6), 0.4403989, 1e-7);
  EXPECT_DOUBLE_EQ(cumulative_fragment_distribution(400e-6, 400e-6), 1.0);
  // monotone in the fragment size
  double last = 0.0;
  for (double d = 10e-6; d <= 400e-6; d += 10e-6) {
    const double b = cumulative_fragment_distribution(d, 400e-6);
    EXPECT_GT(b, last);
    last = b;
  }
}

// ---------------------------------------------------------------- defaults

TEST(Paper001Defaults, DerivedValues) {
  EXPECT_NEAR(defaults::kEnvelopeDensity, 1081.5, 1e-12);
  EXPECT_NEAR(defaults::kTgLiquid - props::kT0, -135.0, 1e-12);
  EXPECT_NEAR(defaults::kTgSolid - props::kT0, 167.0, 1e-12);
  EXPECT_EQ(defaults::kAntoineA, 16.262);
}

// ---------------------------------------------------------------- AD: Jet derivatives vs finite differences

TEST(Paper001Correlations, JetDerivativesMatchFiniteDifferences) {
  const double rho = props::dry_air_density(kT60, kP);
  const double mu = props::air_viscosity(kT60);
  // u_mf in d (Eqs. (31)-(33))
  expect_jet_matches_fd(
      [&](auto d) {
        using T = decltype(d);
        return wen_yu_umf(d, T(1081.5), T(rho), T(mu));
      },
      200e-6, 1e-9, 1e-6);
  // bulk Sherwood in Re (Eqs. (74), (75))
  expect_jet_matches_fd(
      [](auto re) {
        using T = decltype(re);
        return bulk_sherwood(sherwood_single(re, T(0.94)), re, T(0.94), T(1600.0));
      },
      8.0, 1e-5, 1e-7, 2);
  // Gordon-Taylor in X, and the sticky probability through it (Eqs. (53), (54))
  expect_jet_matches_fd(
      [](auto x) {
        using T = decltype(x);
        return sticky_probability(T(360.0), gordon_taylor(x));
      },
      0.12, 1e-7, 1e-6, 5);
  // a calibrated parameter: d C_f / d ln(beta0) = C_f (Eq. (37))
  expect_jet_matches_fd(
      [](auto lnb) {
        using T = decltype(lnb);
        return collision_frequency(T(1e-4), T(3e-4), lnb);
      },
      -17.24, 1e-5, 1e-7, 7);
  // regularized normalized moisture in X on both sides of its kinks (Eq. (80))
  expect_jet_matches_fd(
      [](auto x) {
        using T = decltype(x);
        return normalized_moisture(x, T(0.02), T(0.07)).value;
      },
      0.05, 1e-7, 1e-8);
  expect_jet_matches_fd(
      [](auto x) {
        using T = decltype(x);
        return normalized_moisture(x, T(0.068), T(0.07)).value;
      },
      0.075, 1e-7, 1e-8);
  // BET through the water activity at the solids temperature (Eqs. (81)-(83))
  expect_jet_matches_fd(
      [](auto t) {
        using T = decltype(t);
        return bet_equilibrium_moisture(water_activity(T(0.02), t, T(kP)));
      },
      320.0, 1e-4, 1e-6);
  // breakage rate, mm reading (Eq. (92)), and the fragment distribution (Eq. (93))
  expect_jet_matches_fd([](auto d) { return breakage_rate(d, BreakageSizeUnit::kMillimetre); }, 300e-6, 1e-10, 1e-6);
  expect_jet_matches_fd(
      [](auto d) {
        using T = decltype(d);
        return cumulative_fragment_distribution(d, T(400e-6));
      },
      80e-6, 1e-10, 1e-6);
}

}  // namespace
}  // namespace granuflow::kernels
