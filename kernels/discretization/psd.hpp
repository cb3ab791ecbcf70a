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
// A size statistic (d_x, mean, Sauter diameter, standard deviation) of an empty population or stream: undefined,
// never 0, which reads as a size (issue 29). NaN in the time series; summaries show null and say why.
template <class T>
T undefined_size() {
  return T(std::nan(""));
}
// The same from the mass (or volume) of each of the n cells between the n + 1 diameter edges (m); negative
// amounts count as empty. A template, so that sensitivities of d_x to the class masses are exact (Jets).
template <class T>
void characteristic_diameters_of_mass(const std::vector<double>& d, const T* mass, const double* x, int count, T* out);
template <class T>
T characteristic_diameter_of_mass(const std::vector<double>& d, const T* mass, double x) {
  T out;
  characteristic_diameters_of_mass(d, mass, &x, 1, &out);
  return out;
}
// Several at once (fractions x[0..count-1] into out), sharing one pass over the distribution: a summary's d10, d50,
// d90 and the rest at every output time.
template <class T>
void characteristic_diameters_of_mass(const std::vector<double>& d, const T* mass, const double* x, int count, T* out) {
  for (int k = 0; k < count; ++k)
    if (!(x[k] > 0 && x[k] < 1))
      throw ConfigError(violation("characteristic diameter fraction", x[k], "", "0 < x < 1"));
  const int n = static_cast<int>(d.size()) - 1;
  std::vector<T> q(n + 1, T(0.0));  // Q3 at the edges
  for (int i = 0; i < n; ++i) q[i + 1] = q[i] + (mass[i] > 0.0 ? mass[i] : T(0.0));
  const T total = q[n];
  if (!(total > 0.0)) {
    for (int k = 0; k < count; ++k) out[k] = undefined_size<T>();
    return;
  }
  for (int i = 0; i <= n; ++i) q[i] = q[i] / total;
  for (int k = 0; k < count; ++k) {
    out[k] = T(d[n]);
    for (int i = 0; i < n; ++i) {
      const T &lo = q[i], &hi = q[i + 1];
      using std::pow;
      if (hi >= x[k] && hi > lo) {
        out[k] = d[i] * pow(d[i + 1] / d[i], (x[k] - lo) / (hi - lo));
        break;
      }
    }
  }
}

}  // namespace granuflow::kernels
