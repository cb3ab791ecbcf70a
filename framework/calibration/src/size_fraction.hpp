// Measured size distributions as calibration data: the observable "unit.Q3(<size>)" (e.g. "bed.Q3(500 um)") is the
// cumulative mass fraction of the unit's particles below that size, from the class masses the unit reports as its
// size distribution (psd_m_i) on its class edges d_0 < ... < d_n:
//   Q3(s) = sum_i w_i m_i / sum_i m_i,  w_i = 1 for d_{i+1} <= s,  ln(s / d_i) / ln(d_{i+1} / d_i) in the cell
//   holding s, 0 above;
// the class's mass spread uniformly over ln d, the inverse of how d50 is read from the grid (kernels psd.hpp), and
// linear in the class masses, so dQ3/dp follows exactly from their sensitivities. Negative masses count as empty.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "granuflow/flowsheet.hpp"

namespace granuflow::calib {

struct SizeFraction {
  std::string unit;
  double size = 0.0;      // m
  int first_output = 0;   // flowsheet output index of psd_m_0 (class i at + i)
  std::vector<double> w;  // weight of each class
};

// nullopt when `name` is not of the form unit.Q3(size); ConfigError when it is but the unit is unknown, reports no
// size distribution with class edges, or the size is not a positive length.
std::optional<SizeFraction> size_fraction(const Flowsheet& fs, const std::string& name);

// Q3 at the class masses m (n values, flowsheet output order), and dQ3/dm_i into dq when not null.
double size_fraction_value(const SizeFraction& f, const double* m, double* dq);

}  // namespace granuflow::calib
