// The log-spaced size grid of paper 001 (Table 5: pivots from 50 to 1000 um, 10 classes), read from a unit's
// settings. Units that exchange per-class streams read the same three settings and declare the pivots on
// their ports, so a mismatch is caught when the scene is connected.
#pragma once
#include <cmath>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {

// n >= 2 diameters from lo to hi (both included), equally spaced in ln d.
inline std::vector<double> log_spaced(double lo, double hi, int n) {
  std::vector<double> d(n);
  for (int i = 0; i < n; ++i) d[i] = lo * std::pow(hi / lo, double(i) / (n - 1));
  return d;
}

inline std::vector<double> log_spaced_pivots(Settings& st) {
  namespace def = kernels::paper001::defaults;
  const int n = static_cast<int>(st.get_int("classes", def::kSizeClasses, 3, 200, "size classes, log-spaced pivots"));
  const double lo = st.get_real("d_min", def::kDiameterMin, 1e-7, 1e-2, "smallest pivot diameter, m (Table 5)");
  const double hi = st.get_real("d_max", def::kDiameterMax, 1e-7, 1e-1, "largest pivot diameter, m (Table 5)");
  if (!(hi > lo))
    throw ConfigError(violation(st.where() + ".d_max", hi, "m", "d_max > d_min (" + std::to_string(lo) + ")"));
  return log_spaced(lo, hi, n);
}

}  // namespace granuflow::units
