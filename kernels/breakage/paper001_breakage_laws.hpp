// Breakage laws of paper 001 (Eqs. (90)-(93)): the Vogel-Peukert selection rate and a power-law cumulative
// fragment distribution with a tanh cut-off. Pure functions; the discretization lives in kernels/discretization.
//
// Templates on the scalar type T (double or ceres::Jet). Arguments in SI (diameters in m, energies in J/kg);
// Eq. (92) is a dimensional fit whose diameter unit the paper does not state: micrometres by default
// (docs/paper001_decisions.md), millimetres as an option; the conversion happens inside breakage_rate().
#pragma once
#include <cmath>
#include <string>

#include "granuflow/errors.hpp"
#include "paper001_defaults.hpp"

namespace granuflow::kernels::paper001 {

enum class BreakageSizeUnit { kMicrometre, kMillimetre };

inline std::string to_string(BreakageSizeUnit u) { return u == BreakageSizeUnit::kMicrometre ? "um" : "mm"; }

inline BreakageSizeUnit breakage_size_unit_from_string(const std::string& name) {
  if (name == "um") return BreakageSizeUnit::kMicrometre;
  if (name == "mm") return BreakageSizeUnit::kMillimetre;
  throw ConfigError("breakage_size_unit = '" + name + "': violates one of {um, mm}");
}

// Diameter in the fit's unit per metre.
inline double per_metre(BreakageSizeUnit u) { return u == BreakageSizeUnit::kMicrometre ? 1e6 : 1e3; }

// Eq. (91), paper 001: mass-based impact energy, J/kg, growing linearly with size from E_m,min at d_min,break.
template <class T>
T impact_energy(const T& d, const T& e_min, const T& d_min) {
  return d * e_min / d_min;
}

// Eq. (90), paper 001: 1/s; d in the fit's size unit. A particle whose impact energy does not exceed the
// threshold does not break: the rate is 0 there instead of the negative value the exponential would give.
template <class T>
T vogel_peukert_rate(const T& d, const T& e_kin, const T& e_min, const T& k_break, const T& f_mat) {
  using std::expm1;
  const T x = f_mat * d * (e_kin - e_min);
  return x > 0.0 ? T(-k_break * expm1(-x)) : T(0.0);
}

// Eq. (92), paper 001 (Eqs. (90) and (91) combined), d and d_min in m; Table 10 defaults.
// With um, K is within 3 % of k' for every d >= 60 um; with mm it still grows up to ~1 mm.
template <class T>
T breakage_rate(const T& d, BreakageSizeUnit unit = BreakageSizeUnit::kMicrometre,
                const T& k_break = T(defaults::kBreakageRate), const T& d_min = T(defaults::kBreakageDiameterMin),
                const T& f_mat = T(defaults::kMaterialParameter), const T& e_min = T(defaults::kBreakageEnergyMin)) {
  const double s = per_metre(unit);
  const T d_fit = d * s;
  return vogel_peukert_rate(d_fit, impact_energy(d_fit, e_min, T(d_min * s)), e_min, k_break, f_mat);
}

// The tanh cut-off factor of Eq. (93): ~0.12 at zero size, 0.5 at d_min, -> 1 above ~2 d_min.
template <class T>
T fragment_cutoff(const T& d, const T& d_min) {
  using std::tanh;
  return 0.5 * (1.0 + tanh((d - d_min) / d_min));
}

// Eq. (93), paper 001: cumulative distribution of fragments of size <= d_fragment from a parent of size
// d_parent. Read as docs/paper001_decisions.md fixes it: power law in d_fragment / d_parent, tanh cut-off on the
// fragment size, divided by the cut-off at the parent so that b_cum(d_parent, d_parent) = 1. Only ratios enter,
// so the size unit does not matter.
template <class T>
T cumulative_fragment_distribution(const T& d_fragment, const T& d_parent, const T& q = T(defaults::kFragmentExponent),
                                   const T& d_min = T(defaults::kFragmentDiameterMin)) {
  using std::pow;
  return pow(d_fragment / d_parent, q) * fragment_cutoff(d_fragment, d_min) / fragment_cutoff(d_parent, d_min);
}

}  // namespace granuflow::kernels::paper001
