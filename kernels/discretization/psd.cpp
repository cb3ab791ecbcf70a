#include "discretization/psd.hpp"

#include <cmath>
#include <vector>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

double volume_moment(const Grid& g, const double* N, int k) {
  double s = 0;
  for (int i = 0; i < g.size(); ++i) s += N[i] * std::pow(g.pivot(i), k);
  return s;
}

double diameter_moment(const Grid& g, const double* N, int k) {
  double s = 0;
  for (int i = 0; i < g.size(); ++i) s += N[i] * std::pow(g.diameter_pivots()[i], k);
  return s;
}

void number_density(const Grid& g, const double* N, double* out) {
  for (int i = 0; i < g.size(); ++i) out[i] = N[i] / g.width(i);
}

void volume_density(const Grid& g, const double* N, double* out) {
  for (int i = 0; i < g.size(); ++i) out[i] = N[i] * g.pivot(i) / g.width(i);
}

void mass_density(const Grid& g, const double* N, double rho, double* out) {
  volume_density(g, N, out);
  for (int i = 0; i < g.size(); ++i) out[i] *= rho;
}

double characteristic_diameter(const Grid& g, const double* N, double x) {
  std::vector<double> volume(g.size());
  for (int i = 0; i < g.size(); ++i) volume[i] = N[i] * g.pivot(i);
  return characteristic_diameter_of_mass(g.diameter_edges(), volume.data(), x);
}

}  // namespace granuflow::kernels
