// Parameter values of paper 001 (Stoeckl et al., GF25 batch agglomeration of maltodextrin), Tables 5-10, in SI,
// plus the defaults docs/paper001_decisions.md adds where the paper is silent. Unit ParamSpecs take their defaults
// from here, so each number exists once. Temperatures that the paper gives in degC are stored in K; the
// paper's value stays in the comment.
#pragma once
#include "granuflow/properties.hpp"

namespace granuflow::kernels::paper001::defaults {

// --- Table 5: numerics and loss-function standard deviations ---
inline constexpr double kDiameterMin = 50e-6;           // m (50 um), smallest pivot
inline constexpr double kDiameterMax = 1000e-6;         // m (1000 um), largest pivot
inline constexpr int kSizeClasses = 10;                 // -, log-spaced
inline constexpr double kSdMoisture = 0.01;             // kg/kg (1 wt%), solid moisture content
inline constexpr double kSdGasOutletTemperature = 2.0;  // K (2 degC), outlet gas temperature
inline constexpr double kSdRelD5ToD50 = 0.07;           // -, relative (7 %), d5,3 d10,3 d16,3 d25,3 d50,3
inline constexpr double kSdRelD75 = 0.08;               // -, relative (8 %)
inline constexpr double kSdRelD84 = 0.09;               // -, relative (9 %)
inline constexpr double kSdRelD90 = 0.10;               // -, relative (10 %)
inline constexpr double kSdRelD95 = 0.11;               // -, relative (11 %)

// --- Table 6: reactor and materials ---
inline constexpr double kBedArea = 0.25;                 // m^2, bed cross-section (A_inlet)
inline constexpr double kWallArea = 7.3;                 // m^2
inline constexpr double kEquipmentVolume = 1.2;          // m^3
inline constexpr double kSolidSkeletalDensity = 1545.0;  // kg/m^3
inline constexpr double kSolidCp = 1220.0;               // J/(kg K)
inline constexpr double kLiquidDensity = 1000.0;         // kg/m^3
inline constexpr double kLiquidCp = 4180.0;              // J/(kg K)
inline constexpr double kLiquidViscosity = 1e-3;         // Pa s
inline constexpr double kVapourDiffusivity = 2.0e-5;     // m^2/s, water vapour in air (D in Eqs. (73), (78))
inline constexpr double kGasConductivity = 2.4e-2;       // W/(m K), lambda_g in Eqs. (86), (89)

// --- Table 7: initial conditions and process parameters ---
inline constexpr double kGasHoldup = 1.53;                 // kg, "mass wet air" = dry-air hold-up [DECISIONS]
inline constexpr double kBulkDensity = 560.0;              // kg/m^3
inline constexpr double kIntraParticleVoidFraction = 0.3;  // m^3/m^3
inline constexpr double kSprayTemperature = 283.15;        // K (10 degC)
// Envelope density for size <-> mass: rho_s (1 - eps_intra) = 1545 * 0.7 [DECISIONS].
inline constexpr double kEnvelopeDensity = kSolidSkeletalDensity * (1.0 - kIntraParticleVoidFraction);  // kg/m^3

// --- Table 8: heat and mass transfer ---
inline constexpr double kWallHeatTransfer = 13.8;        // W/(m^2 K), Eq. (84)
inline constexpr double kTauC1 = -3e-3;                  // -, Eq. (29) slope on Re ("wetting coefficient 1")
inline constexpr double kTauC2 = 0.23;                   // -, Eq. (29) intercept
inline constexpr double kEvaporationCoefficient = 3e-3;  // kg/m^2 per unit Delta Y, Eq. (66) [DECISIONS]
inline constexpr double kCriticalMoisture = 0.07;        // kg/kg dry, X_cr in Eq. (80)
inline constexpr double kBulkSherwoodCorrection = 1.0;   // -, eps in Eq. (74)
inline constexpr double kBetMonolayer = 0.037;           // kg/kg dry (3.7 wt%), m_m in Eq. (81)
inline constexpr double kBetN = 11.9;                    // -, n in Eq. (81)
inline constexpr double kAntoineA = props::kAntoineA;    // -, Eq. (69), p in kPa, T in degC
inline constexpr double kAntoineB = props::kAntoineB;    // degC
inline constexpr double kAntoineC = props::kAntoineC;    // degC

// --- Table 9: agglomeration and glass-transition success factor ---
inline constexpr double kLnBeta0 = -17.24;           // ln(beta0), beta0 with d in m, Eq. (37) [DECISIONS]
inline constexpr double kDropletDiameter = 30e-6;    // m (30 um)
inline constexpr double kStickyOffset = 20.0;        // K (20 degC difference), C2 in Eq. (53)
inline constexpr double kStickySlope = 8.733;        // K, C1 in Eq. (53)
inline constexpr double kGordonTaylorK = 6.4;        // -, k in Eq. (54)
inline constexpr double kTgLiquid = 138.15;          // K (-135 degC), water
inline constexpr double kTgSolid = 440.15;           // K (167 degC), maltodextrin (printed as "liquid" too)
inline constexpr double kSprayZoneDiameter = 0.3;    // m, Eq. (48)
inline constexpr double kWsC1 = -3e-4;               // -, Eq. (47) Re^2 coefficient
inline constexpr double kWsC2 = 5.5e-3;              // -, Eq. (47) Re coefficient
inline constexpr double kWsC3 = 0.13;                // -, Eq. (47) intercept
inline constexpr double kVelocityC1 = 1.0e-2;        // m/s, Eq. (49) Re coefficient
inline constexpr double kVelocityC2 = 6.6e-2;        // m/s, Eq. (49) intercept
inline constexpr double kPenetrationDepth = 168e-6;  // m (168 um), Eq. (57)
inline constexpr double kDropletDensity = 1000.0;    // kg/m^3, rho_d in Eq. (42)
inline constexpr double kParticleDensity = 900.0;    // kg/m^3, rho_env in Eq. (42) and rho_p in Eq. (33) [DECISIONS]
inline constexpr double kTauSpray = 0.22;            // -, tau_spray in Eq. (37)

// --- Table 10: breakage ---
inline constexpr double kBreakageRate = 1.3e-3;        // 1/s, k'_break in Eq. (92)
inline constexpr double kBreakageDiameterMin = 50e-6;  // m (50 um), d_min,break
inline constexpr double kMaterialParameter = 1.0;      // -, f_Mat (units absorb the size unit of Eq. (92))
inline constexpr double kBreakageEnergyMin = 0.3;      // J/kg ("mass based"; the table prints J), E_m,min
inline constexpr double kFragmentExponent = 0.5;       // -, q in Eq. (93)
inline constexpr double kFragmentDiameterMin = 50e-6;  // m (50 um), d_j,min in Eq. (93)

// --- docs/paper001_decisions.md: regularizations (each reported when active) ---
inline constexpr double kWsFloor = 0.05;              // -, floor of Eq. (47) (the fit turns negative at Re ~ 32)
inline constexpr double kEtaDenominatorFloor = 0.01;  // kg/kg, floor of X_cr - X_eq in Eq. (80)
inline constexpr double kEtaMin = -1.0;               // -, limit of re-adsorption in Eq. (80)
inline constexpr double kWetVolumeFractionCap = 1.0;  // -, V_wet / V_particle in Eqs. (56)-(57)

}  // namespace granuflow::kernels::paper001::defaults
