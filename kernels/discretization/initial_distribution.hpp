// Initial particle size distributions on the grid. A continuous distribution is integrated exactly over each
// cell (number B_i and volume V_i of the particles in [e_i, e_{i+1}]) and then put on the pivots:
//   * kMoments: the packet (B_i, V_i) is split with the cell average rule (redistribution.hpp), so the total
//     number and volume of the grid equal those of the distribution inside [e_0, e_n] (what the split sends
//     to a virtual pivot is kept, volume-conserving, in the first / last class);
//   * kNumber:  N_i = B_i (number exact, volume off by the cell's spread);
//   * kMass:    N_i = V_i / x_i (volume exact, number off).
// Written on T so that sensitivities of the initial state to the distribution parameters are exact.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "discretization/grid.hpp"
#include "discretization/redistribution.hpp"

namespace granuflow::kernels {

enum class Binning { kMoments, kNumber, kMass };
std::string to_string(Binning b);
Binning binning_from_string(const std::string& s);  // throws ConfigError listing moments, number, mass

// Exponential number density n(v) = (N0 / v0) exp(-v / v0): number and volume in each cell.
template <class T>
void exponential_cells(const Grid& g, const T& n0, const T& v0, T* number, T* volume) {
  using std::exp;
  using std::expm1;
  for (int i = 0; i < g.size(); ++i) {
    const T a = g.edge(i) / v0, h = g.width(i) / v0, ea = exp(-a);
    number[i] = -n0 * ea * expm1(-h);
    // int_a^b v e^-v dv = e^-a [(1 + a)(1 - e^-h) - h e^-h], in units of v0
    volume[i] = n0 * v0 * ea * (-(1.0 + a) * expm1(-h) - h * exp(-h));
  }
}

// Log-normal distribution in mass over the diameter (paper 001's initial PSD, docs/paper001_decisions.md): total
// particle volume v_total (m^3), mass median diameter d50_3 (m), geometric standard deviation sigma_g (-).
// The number distribution is then log-normal with median d50_3 exp(-3 ln^2 sigma_g) (Hatch-Choate).
template <class T>
void lognormal_mass_cells(const Grid& g, const T& v_total, const T& d50_3, const T& sigma_g, T* number, T* volume) {
  using std::erfc;
  using std::exp;
  using std::log;
  const T s = log(sigma_g);
  const T d50_0 = d50_3 * exp(-3.0 * s * s);
  const T mean_volume = (3.14159265358979323846 / 6.0) * d50_0 * d50_0 * d50_0 * exp(4.5 * s * s);
  const T n_total = v_total / mean_volume;
  auto cdf = [&](double d, const T& median) { return 0.5 * erfc(-(log(d) - log(median)) / (s * std::sqrt(2.0))); };
  const auto& de = g.diameter_edges();
  for (int i = 0; i < g.size(); ++i) {
    number[i] = n_total * (cdf(de[i + 1], d50_0) - cdf(de[i], d50_0));
    volume[i] = v_total * (cdf(de[i + 1], d50_3) - cdf(de[i], d50_3));
  }
}

// Puts cell integrals on the pivots (see Binning).
template <class T>
void bin_cells(const Grid& g, Binning binning, const T* number, const T* volume, T* N) {
  const int n = g.size();
  if (binning == Binning::kNumber) {
    for (int i = 0; i < n; ++i) N[i] = number[i];
    return;
  }
  if (binning == Binning::kMass) {
    for (int i = 0; i < n; ++i) N[i] = volume[i] / g.pivot(i);
    return;
  }
  std::vector<T> out(n + kOutsideRows, T(0.0));
  for (int i = 0; i < n; ++i)
    split_between(g, volume[i] >= g.pivot(i) * number[i] ? i : i - 1, number[i], volume[i], out.data());
  out[0] += out[n + kVolumeBelow] / g.pivot(0);
  out[n - 1] += out[n + kVolumeAbove] / g.pivot(n - 1);
  for (int i = 0; i < n; ++i) N[i] = out[i];
}

}  // namespace granuflow::kernels
