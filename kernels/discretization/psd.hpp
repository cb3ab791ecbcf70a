// Statistics of a population on a Grid: moments, densities and the mass-based characteristic diameters.
//
// d_{x,3} (x in (0, 1); d10,3 / d50,3 / d90,3 for x = 0.1 / 0.5 / 0.9) is read from the cumulative mass (volume)
// distribution Q3, known exactly at the cell edges, Q3(d_{i+1}) = sum_{j <= i} N_j x_j / sum_j N_j x_j, and
// interpolated linearly in ln d inside a cell (the class's mass spread uniformly over ln d):
//     d_x = d_i (d_{i+1} / d_i)^((x - Q3(d_i)) / (Q3(d_{i+1}) - Q3(d_i))).
#pragma once
#include <cmath>
#include <vector>

#include "discretization/grid.hpp"
#include "granuflow/errors.hpp"

namespace granuflow::kernels {

// sum_i N_i x_i^k (volume moments; k = 0 number, k = 1 volume).
double volume_moment(const Grid& g, const double* N, int k);
// sum_i N_i d_i^k (diameter moments).
double diameter_moment(const Grid& g, const double* N, int k);
// Densities per unit particle volume, 1/m^3 (number), m^3/m^3 (volume) or kg/m^3 (mass, volume times rho).
void number_density(const Grid& g, const double* N, double* out);
void volume_density(const Grid& g, const double* N, double* out);
void mass_density(const Grid& g, const double* N, double rho, double* out);
// Mass-based characteristic diameter d_{x,3}, m; NaN for an empty population.
double characteristic_diameter(const Grid& g, const double* N, double x);
// The same from the mass (or volume) of each of the n cells between the n + 1 diameter edges (m); negative
// amounts count as empty. A template, so that sensitivities of d_x to the class masses are exact (Jets).
template <class T>
T characteristic_diameter_of_mass(const std::vector<double>& d, const T* mass, double x) {
  if (!(x > 0 && x < 1)) throw ConfigError(violation("characteristic diameter fraction", x, "", "0 < x < 1"));
  const int n = static_cast<int>(d.size()) - 1;
  std::vector<T> q(n + 1, T(0.0));
  for (int i = 0; i < n; ++i) q[i + 1] = q[i] + (mass[i] > 0.0 ? mass[i] : T(0.0));
  if (!(q[n] > 0.0)) return T(std::nan(""));
  for (int i = 0; i < n; ++i) {
    const T lo = q[i] / q[n], hi = q[i + 1] / q[n];
    using std::pow;
    if (hi >= x && hi > lo) return d[i] * pow(d[i + 1] / d[i], (x - lo) / (hi - lo));
  }
  return T(d[n]);
}

}  // namespace granuflow::kernels
