// Spray-zone closures of paper 001 (Eqs. (29), (34)-(57)): the DEM surrogates (residence time, solids hold-up,
// particle velocity), the size-resolved liquid split, the Kariuki coating number and surface coverage, the
// wet-spot glass transition (Gordon-Taylor) and stickiness, and the EKE collision frequency of the
// agglomeration kernel beta_ij = C_f,spray psi_geom psi_phys.
//
// Templates on the scalar type T (double or ceres::Jet); SI units (diameters in m, temperatures in K).
// The Reynolds number of the surrogates is Eq. (30) (transfer::excess_reynolds_number). Closures that may
// leave the printed equation (a floor or a cap from docs/paper001_decisions.md) return Limited<T> so units count it.
#pragma once
#include <cmath>
#include <cstddef>
#include <string>

#include "granuflow/errors.hpp"
#include "limited.hpp"
#include "paper001_defaults.hpp"
#include "particle_geometry.hpp"
#include "simd_math.hpp"

namespace granuflow::kernels::paper001 {

// --- DEM surrogates ---

// Eq. (29), paper 001: fraction of time a class spends in the spray zone (Table 8). Positive up to
// Re = C2 / -C1 = 76.7, beyond paper 001's operating window (Re < 40 for d <= 1 mm at 600-800 m^3/h), so it
// is not floored.
template <class T>
T dimensionless_residence_time(const T& re, const T& c1 = T(defaults::kTauC1), const T& c2 = T(defaults::kTauC2)) {
  return c1 * re + c2;
}

// Eq. (34), paper 001: tau_norm[i] = tau[i] / sum(tau), for n classes.
template <class T>
void normalize_residence_times(const T* tau, std::size_t n, T* tau_norm) {
  T sum(0.0);
  for (std::size_t i = 0; i < n; ++i) sum += tau[i];
  for (std::size_t i = 0; i < n; ++i) tau_norm[i] = tau[i] / sum;
}

// How Eqs. (35), (44), (64) weight the classes. The printed weight tau_i d_i^2 is per particle, so a class
// with few particles would get as much liquid as a full one; kClassSurface multiplies by the class particle
// count N_i (class surface x residence), the default of docs/paper001_decisions.md.
enum class LiquidSplit { kClassSurface, kLiteral };

inline std::string to_string(LiquidSplit s) { return s == LiquidSplit::kClassSurface ? "class_surface" : "literal"; }

inline LiquidSplit liquid_split_from_string(const std::string& name) {
  if (name == "class_surface") return LiquidSplit::kClassSurface;
  if (name == "literal") return LiquidSplit::kLiteral;
  throw ConfigError("liquid_split = '" + name + "': violates one of {class_surface, literal}");
}

// Eqs. (35), (44), (64), paper 001: split m_liquid (kg/s, the spray after droplet evaporation in Eq. (44)) over
// n classes into m_deposition. `number` (particles per class) is read only for kClassSurface.
template <class T>
void distribute_liquid(const T* tau, const T* d, const T* number, std::size_t n, const T& m_liquid, LiquidSplit split,
                       T* m_deposition) {
  T sum(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    m_deposition[i] = tau[i] * d[i] * d[i];
    if (split == LiquidSplit::kClassSurface) m_deposition[i] *= number[i];
    sum += m_deposition[i];
  }
  for (std::size_t i = 0; i < n; ++i) m_deposition[i] *= m_liquid / sum;
}

// Eq. (47), paper 001: solids mass fraction of a class inside the spray zone (Table 9). The fit turns negative
// at Re ~ 32, so it is floored (docs/paper001_decisions.md; the floor is a parameter).
template <class T>
Limited<T> spray_zone_solids_fraction(const T& re, const T& floor = T(defaults::kWsFloor),
                                      const T& c1 = T(defaults::kWsC1), const T& c2 = T(defaults::kWsC2),
                                      const T& c3 = T(defaults::kWsC3)) {
  return floor_at(T((c1 * re + c2) * re + c3), floor);
}

// Eq. (49), paper 001: mean particle velocity in the spray zone, m/s (Table 9).
template <class T>
T spray_zone_particle_velocity(const T& re, const T& c1 = T(defaults::kVelocityC1),
                               const T& c2 = T(defaults::kVelocityC2)) {
  return c1 * re + c2;
}

// Eq. (48), paper 001: time to cross the spray zone once, s.
template <class T>
T spray_zone_crossing_time(const T& v, const T& d_sprayzone = T(defaults::kSprayZoneDiameter)) {
  return d_sprayzone / v;
}

// Eq. (46), paper 001: solids mass of a class inside the spray zone, kg.
template <class T>
T spray_zone_holdup(const T& w_s, const T& m_bed_class) {
  return w_s * m_bed_class;
}

// Eq. (45), paper 001: solids mass flow of a class through the spray zone, kg/s (hold-up over crossing time,
// docs/paper001_decisions.md; the paper prints the same symbol on both sides).
template <class T>
T spray_zone_solids_flow(const T& m_holdup, const T& t_spray) {
  return m_holdup / t_spray;
}

// --- wetting and coating ---

// Eq. (43), paper 001: liquid loading of the solids passing the spray zone, kg/kg.
template <class T>
T moisture_loading(const T& m_deposition, const T& m_solids_flow) {
  return m_deposition / m_solids_flow;
}

// Eq. (42), paper 001, with A_contact from Eq. (50) and A_p from Eq. (51): Kariuki coating number.
// rho_env is the 900 kg/m^3 of Table 9 (docs/paper001_decisions.md), not the 1081.5 used for size <-> mass.
template <class T>
T coating_number(const T& x_ls, const T& d, const T& d_d, const T& rho_env = T(defaults::kParticleDensity),
                 const T& rho_d = T(defaults::kDropletDensity)) {
  return x_ls * d * d * d * rho_env * sphere_cross_section(d_d) / (d_d * d_d * d_d * rho_d * sphere_surface(d));
}

// Eq. (41), paper 001: fraction of the particle surface covered by liquid (expm1 keeps small phi exact).
template <class T>
T surface_coverage(const T& phi) {
  using std::expm1;
  return -expm1(-phi);
}

// Probability that at least one of two independent events happens: the shape of Eqs. (40) and (52).
template <class T>
T either_of(const T& p_i, const T& p_j) {
  return 1.0 - (1.0 - p_i) * (1.0 - p_j);
}

// Eq. (40), paper 001: the collision meets a wet spot on at least one partner.
template <class T>
T geometric_success_factor(const T& f_wet_i, const T& f_wet_j) {
  return either_of(f_wet_i, f_wet_j);
}

// Eq. (57), paper 001, before the cap of wetted_volume_fraction(): h_pen A f_wet / V of a particle of diameter d.
template <class T>
T wetted_volume_ratio(const T& f_wet, const T& d, const T& h_pen) {
  return h_pen * sphere_surface(d) * f_wet / sphere_volume(d);
}

// Eq. (57), paper 001, as the fraction V_wet / V_particle that Eq. (56) needs: a cylinder of depth h_pen under
// the wetted surface. Capped at `cap` (1: the whole particle, docs/paper001_decisions.md) because h_pen A f_wet exceeds
// the particle volume for d < 6 h_pen f_wet.
template <class T>
Limited<T> wetted_volume_fraction(const T& f_wet, const T& d, const T& h_pen = T(defaults::kPenetrationDepth),
                                  const T& cap = T(defaults::kWetVolumeFractionCap)) {
  return cap_at(wetted_volume_ratio(f_wet, d, h_pen), cap);
}

// Eq. (57), paper 001, as a volume (m^3), capped at the particle volume like wetted_volume_fraction().
template <class T>
Limited<T> wetted_volume(const T& f_wet, const T& d, const T& h_pen = T(defaults::kPenetrationDepth)) {
  const Limited<T> frac = wetted_volume_fraction(f_wet, d, h_pen);
  return {frac.value * sphere_volume(d), frac.active};
}

// Eq. (56), paper 001: solids flow whose wetted volume receives the deposited liquid, kg/s.
template <class T>
T exposed_solids_flow(const T& m_solids_flow, const T& wet_volume_fraction) {
  return m_solids_flow * wet_volume_fraction;
}

// Eq. (55), paper 001: moisture of the wet spot, kg/kg dry.
template <class T>
T wet_spot_moisture(const T& m_deposition, const T& m_exposed, const T& x0) {
  return m_deposition / m_exposed + x0;
}

// --- glass transition and stickiness ---

// Liquid mass fraction x = X / (1 + X) of a solid with moisture X (kg/kg dry), the x_l of Eq. (54)
// (docs/paper001_decisions.md).
template <class T>
T liquid_mass_fraction(const T& x_dry_basis) {
  return x_dry_basis / (1.0 + x_dry_basis);
}

// Eq. (54), paper 001: Gordon-Taylor glass transition of water-plasticized maltodextrin, K. A weighted mean of
// tg_l and tg_s, so it is the same in K and degC.
template <class T>
T gordon_taylor(const T& x_dry_basis, const T& k = T(defaults::kGordonTaylorK), const T& tg_l = T(defaults::kTgLiquid),
                const T& tg_s = T(defaults::kTgSolid)) {
  const T x = liquid_mass_fraction(x_dry_basis);
  return (k * x * tg_l + (1.0 - x) * tg_s) / (k * x + (1.0 - x));
}

// Eq. (53), paper 001: ~1 % at T = Tg, 50 % at Tg + C2, ~99 % at Tg + 2 C2 for C1 = 8.733 K, C2 = 20 K.
// (tanh z + 1) / 2 is the logistic function 1 / (1 + exp(-2 z)), evaluated in that form: no cancellation far
// below the sticky point (where the printed form rounds to 0 from z < -19), and one exp, which a vector loop takes
// four at a time (kernels/simd_math.hpp), where tanh costs several times as much.
template <class T>
T sticky_probability(const T& temp, const T& tg, const T& c1 = T(defaults::kStickySlope),
                     const T& c2 = T(defaults::kStickyOffset)) {
  using std::exp;
  return 1.0 / (1.0 + exp(-2.0 * ((temp - (c2 + tg)) / c1)));
}

// Eq. (52), paper 001: at least one partner is sticky.
template <class T>
T physical_success_factor(const T& p_sticky_i, const T& p_sticky_j) {
  return either_of(p_sticky_i, p_sticky_j);
}

// --- agglomeration kernel ---

// Eq. (37), paper 001: EKE collision frequency in the spray zone, 1/s per pair with beta0 = exp(ln_beta0),
// d in m and absolute particle numbers (docs/paper001_decisions.md); calibration moves ln_beta0 (Table 9: -17.24).
template <class T>
T collision_frequency(const T& d_i, const T& d_j, const T& ln_beta0 = T(defaults::kLnBeta0),
                      const T& tau_spray = T(defaults::kTauSpray)) {
  using std::exp;
  using std::sqrt;
  const T sum = d_i + d_j;
  return exp(ln_beta0) * sum * sum * sqrt(1.0 / (d_i * d_i * d_i) + 1.0 / (d_j * d_j * d_j)) * tau_spray;
}

// Eqs. (36), (38), (39), paper 001.
template <class T>
T agglomeration_kernel(const T& collision_freq, const T& psi_geom, const T& psi_phys) {
  return collision_freq * psi_geom * psi_phys;
}

}  // namespace granuflow::kernels::paper001
