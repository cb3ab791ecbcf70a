// Liquid addition of the 2-D population (unit pbm_2d): where the sprayed liquid goes, as particle moves along the
// liquid axis. Two readings of paper 002 (setting spray):
//   * droplets: section 3.2's DEM picture, a droplet of volume v_d absorbed whole by the one particle it meets, so a
//     particle jumps from l to l + v_d (split between the two liquid pivots around it, number and liquid kept);
//   * continuous: Eq. (6)'s term d(F dl/dt)/dl, liquid spread over the particles as a flow dl/dt per particle,
//     discretized by first-order upwind fluxes to the next liquid class (positive, and they add exactly Q). In the
//     same form as droplets: a flow of R = Q / dl quanta of one liquid step each.
// Who receives the liquid (setting spray_weight): every particle alike (number), in proportion to its surface D^2
// (surface), or, for droplets, to its collision cross-section with a droplet (D + d_drop)^2 (cross_section).
#pragma once
#include <cmath>
#include <vector>

#include "granuflow/unit.hpp"
#include "kernels/discretization/grid2d.hpp"
#include "kernels/population/population2d.hpp"

namespace granuflow::units::pbm2d {

enum class Spray { kNone, kDroplets, kContinuous };
enum class SprayWeight { kNumber, kSurface, kCrossSection };

// The arrivals: R quanta of liquid volume vd per second, weight per bin, their sum W over the particles, and the
// shift vd / dl in liquid steps (lo steps with weight 1 - nu, lo + 1 with nu). n_out, w_out: the particles that left
// the grid and the weight of one (at their mean volume); g_n, g_v: d(w_out n_out)/d(n_out), /d(volume off the grid).
template <class T>
struct Deposit {
  T R = T(0.0), W = T(0.0), nu = T(0.0), vd = T(0.0), n_out = T(0.0), w_out = T(0.0);
  double g_n = 0.0, g_v = 0.0;
  int lo = 0;
  std::vector<T> w;
};

// Q: liquid volume flow (m3/s); dd: droplet diameter (droplets; 0 otherwise); N: bin numbers; n_out, v_out: number
// and volume (solid + liquid) that left the grid (have_out: the unit books them).
template <class T>
Deposit<T> deposit_terms(const kernels::Grid2D& g, Spray spray, SprayWeight weight, const T& Q, const T& dd, const T* N,
                         bool have_out, const T& n_out, const T& v_out) {
  constexpr double kPi = 3.14159265358979323846;
  Deposit<T> d;
  const int n = g.size();
  if (spray == Spray::kDroplets) {
    const T vd = kPi / 6.0 * dd * dd * dd;
    d.R = Q / vd, d.vd = vd;
  } else {  // Eq. (6), paper 002: upwind flux of N dl/dt, one liquid step per quantum
    d.vd = T(g.liquid_step()), d.R = Q / g.liquid_step();
  }
  // the weight's added length: the droplet's diameter for the cross-section, none for the surface
  const T add = weight == SprayWeight::kCrossSection ? dd : T(0.0);
  d.w.resize(n);
  for (int a = 0; a < n; ++a) {
    const T s = g.diameter(a) + add;
    d.w[a] = weight == SprayWeight::kNumber ? T(1.0) : T(s * s);
    d.W += d.w[a] * N[a];
  }
  if (have_out && value_of(n_out) > 0.0) {
    d.n_out = n_out;
    d.w_out = T(1.0), d.g_n = 1.0;
    if (weight != SprayWeight::kNumber && value_of(v_out) > 0.0) {  // at the mean size off the grid
      const T D = cbrt(6.0 / kPi * v_out / d.n_out);
      d.w_out = (D + add) * (D + add);
      d.g_n = value_of(d.w_out - 2.0 / 3.0 * (D + add) * D),
      d.g_v = value_of(2.0 / 3.0 * (D + add) * D * d.n_out / v_out);
    }
    d.W += d.w_out * d.n_out;
  }
  if (spray == Spray::kDroplets) {
    const T x = d.vd / g.liquid_step();
    d.lo = static_cast<int>(std::floor(value_of(x)));
    d.nu = x - double(d.lo);
  } else {
    d.lo = 1, d.nu = T(0.0);
  }
  return d;
}

// Where one particle of bin a goes when it receives a quantum, as (row, amount per particle): its own row -1, the two
// liquid pivots around l_j + v_d, or the outside rows (number, solid and liquid volume) beyond the axis. row0: the
// row of bin 0; out[k]: the outside rows (kernels::kOut2Number, kOut2Solid, kOut2Liquid).
template <class T, class F>
void place_deposit(const kernels::Grid2D& g, int a, const Deposit<T>& d, int row0, const int* out, F&& add) {
  const int nl = g.nl(), i = a / nl, j = a % nl;
  add(row0 + a, T(-1.0));
  const int L[2] = {j + d.lo, j + d.lo + 1};
  const T f[2] = {T(1.0 - d.nu), d.nu};
  for (int k = 0; k < 2; ++k) {
    if (L[k] < nl) {
      add(row0 + g.bin(i, L[k]), f[k]);
    } else {
      add(out[kernels::kOut2Number], f[k]);
      add(out[kernels::kOut2Solid], T(f[k] * g.solid().pivot(i)));
      add(out[kernels::kOut2Liquid], T(f[k] * (L[k] * g.liquid_step())));
    }
  }
}

}  // namespace granuflow::units::pbm2d
