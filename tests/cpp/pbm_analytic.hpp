// Analytic solutions of the population balance (docs/verification.md), with N0 = v0 = 1 and n(v, 0) = exp(-v), and
// their integrals over grid cells, shared by the PBM tests and tests/bench/.
#pragma once
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "kernels/discretization/grid.hpp"

namespace granuflow::pbm_analytic {

inline constexpr double kPi = 3.14159265358979323846;

// Constant kernel beta = 1 (Scott 1968): s = 1 + t/2.
inline double scott_m0(double t) { return 1.0 / (1.0 + 0.5 * t); }
inline double scott_m2(double t) { return 2.0 + t; }
inline double scott_density(double v, double t) {
  const double s = 1.0 + 0.5 * t;
  return std::exp(-v / s) / (s * s);
}

// exp(-z) I1(z), exact for moderate z and by its asymptotic series where I1 overflows.
inline double scaled_bessel_i1(double z) {
  if (z < 500.0) return std::cyl_bessel_i(1.0, z) * std::exp(-z);
  const double mu = 4.0;  // 4 nu^2 for nu = 1
  double term = 1.0, sum = 1.0;
  for (int k = 1; k < 8; ++k) {
    term *= -(mu - (2.0 * k - 1) * (2.0 * k - 1)) / (k * 8.0 * z);
    sum += term;
  }
  return sum / std::sqrt(2.0 * kPi * z);
}

// Sum kernel beta = u + v (Golovin): g = 1 - exp(-T).
inline double golovin_m0(double t) { return std::exp(-t); }
inline double golovin_m2(double t) { return 2.0 * std::exp(2.0 * t); }
inline double golovin_density(double v, double t) {
  if (t == 0.0) return std::exp(-v);
  const double g = 1.0 - std::exp(-t), sg = std::sqrt(g), z = 2.0 * v * sg;
  // (1 - g) exp(-(1 + g) v) I1(z) / (v sqrt g), with I1(z) = exp(z) scaled_i1(z)
  return (1.0 - g) * std::exp(-(1.0 + g) * v + z) * scaled_bessel_i1(z) / (v * sg);
}

// Product kernel beta = u v before gelation (t < 1/2).
inline double product_m0(double t) { return 1.0 - 0.5 * t; }
inline double product_m2(double t) { return 2.0 / (1.0 - 2.0 * t); }

// Binary breakage, b = 2/u, S(v) = v (Ziff & McGrady 1985).
inline double ziff_m0(double t) { return 1.0 + t; }
inline double ziff_m2(double t) { return 2.0 / (1.0 + t); }
inline double ziff_density(double v, double t) { return (1.0 + t) * (1.0 + t) * std::exp(-v * (1.0 + t)); }

// Size-independent growth in diameter, dL/dt = G: the number density in L shifts.
inline double volume_of(double L) { return kPi / 6.0 * L * L * L; }
inline double growth_density_L(double L, double shift) {  // n_L(L, t), shift = G t
  const double l0 = L - shift;
  if (l0 <= 0) return 0.0;
  return std::exp(-volume_of(l0)) * 0.5 * kPi * l0 * l0;
}

// Gauss-Legendre integral of f over [a, b] on `panels` panels (8 points each).
inline double integrate(const std::function<double(double)>& f, double a, double b, int panels) {
  static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
  static const double w[4] = {0.3626837833783620, 0.3137066959342412, 0.2223810344533745, 0.1012285362903763};
  const double h = (b - a) / panels;
  double s = 0;
  for (int p = 0; p < panels; ++p) {
    const double m = a + (p + 0.5) * h;
    for (int g = 0; g < 4; ++g) s += w[g] * (f(m - x[g] * 0.5 * h) + f(m + x[g] * 0.5 * h));
  }
  return 0.5 * h * s;
}

// Volume (mass) in each cell of the exact density n(v): int_cell v n(v) dv.
inline std::vector<double> cell_volumes(const kernels::Grid& g, const std::function<double(double)>& n) {
  std::vector<double> out(g.size());
  for (int i = 0; i < g.size(); ++i)
    out[i] = integrate([&](double v) { return v * n(v); }, g.edge(i), g.edge(i + 1), 16);
  return out;
}

// The same for the growth case, integrating over the cell in diameter.
inline std::vector<double> growth_cell_volumes(const kernels::Grid& g, double shift) {
  std::vector<double> out(g.size());
  const auto& d = g.diameter_edges();
  for (int i = 0; i < g.size(); ++i)
    out[i] = integrate([&](double L) { return volume_of(L) * growth_density_L(L, shift); }, d[i], d[i + 1], 16);
  return out;
}

// Moments sum over the exact shifted distribution: int v(L)^k n_L(L, t) dL.
inline double growth_moment(int k, double shift) {
  return integrate([&](double l0) { return std::pow(volume_of(l0 + shift), k) * growth_density_L(l0 + shift, shift); },
                   0.0, 6.0, 600);
}

// Relative L1 error of the discrete mass density: sum |N_i x_i - V_i| / sum V_i.
inline double l1_mass_error(const kernels::Grid& g, const double* N, const std::vector<double>& exact) {
  double num = 0, den = 0;
  for (int i = 0; i < g.size(); ++i) num += std::abs(N[i] * g.pivot(i) - exact[i]), den += exact[i];
  return num / den;
}

}  // namespace granuflow::pbm_analytic
