// Moment-preserving redistribution onto the pivots, shared by the aggregation and breakage schemes.
//
// A packet of particles (number B, volume V, mean volume V/B) that lies between two neighbouring pivots
// x_a <= V/B <= x_{a+1} is split so that number and volume are both kept (Kumar & Ramkrishna 1996, Eq. (9);
// Kumar et al. 2006, Eq. (15)):
//     to x_{a+1}: nu = (V - x_a B) / (x_{a+1} - x_a),     to x_a: B - nu.
// The split is linear in (B, V) for a given interval, which is what makes the schemes' Jacobians cheap.
//
// Rate vectors have n class rows followed by kOutsideRows rows that record what leaves the grid: the number and
// volume that went above the top (to the virtual pivot x_hi or beyond) and the volume that went below the
// bottom (to x_lo or below). Nothing is lost silently: sum_i x_i dN_i/dt + d(volume_above + volume_below)/dt
// equals the volume created (growth) or zero (aggregation, breakage) to round-off.
#pragma once
#include "discretization/grid.hpp"

namespace granuflow::kernels {

inline constexpr int kNumberAbove = 0;
inline constexpr int kVolumeAbove = 1;
inline constexpr int kVolumeBelow = 2;
inline constexpr int kOutsideRows = 3;

// Adds a packet split between extended pivots a and a + 1 (-1 <= a <= n - 1) to `out` (n + kOutsideRows).
template <class T>
void split_between(const Grid& g, int a, const T& number, const T& volume, T* out) {
  const int n = g.size();
  const double xa = g.pivot_ext(a), xb = g.pivot_ext(a + 1);
  const T nu = (volume - xa * number) / (xb - xa);
  const T rest = number - nu;
  if (a >= 0)
    out[a] += rest;
  else
    out[n + kVolumeBelow] += xa * rest;
  if (a + 1 < n)
    out[a + 1] += nu;
  else {
    out[n + kNumberAbove] += nu;
    out[n + kVolumeAbove] += xb * nu;
  }
}

// Coefficients of split_between: d out[row] / dB and d out[row] / dV for the (up to three) rows it touches.
struct SplitRow {
  int row;
  double d_number;
  double d_volume;
};
inline int split_rows(const Grid& g, int a, SplitRow rows[3]) {
  const int n = g.size();
  const double xa = g.pivot_ext(a), xb = g.pivot_ext(a + 1), inv = 1.0 / (xb - xa);
  // nu = (V - xa B) inv: dnu/dB = -xa inv, dnu/dV = inv;  rest = B - nu.
  int k = 0;
  if (a >= 0)
    rows[k++] = {a, 1.0 + xa * inv, -inv};
  else
    rows[k++] = {n + kVolumeBelow, xa * (1.0 + xa * inv), -xa * inv};
  if (a + 1 < n) {
    rows[k++] = {a + 1, -xa * inv, inv};
  } else {
    rows[k++] = {n + kNumberAbove, -xa * inv, inv};
    rows[k++] = {n + kVolumeAbove, -xb * xa * inv, xb * inv};
  }
  return k;
}

// A single particle of volume v (number 1): split over its pivot interval, or wholly outside beyond the
// virtual pivots. Returns the rows and weights (at most three).
struct Weight {
  int row;
  double w;
};
inline int place_particle(const Grid& g, double v, Weight out[3]) {
  const int n = g.size();
  const int a = g.interval_of(v);
  if (a >= n) {
    out[0] = {n + kNumberAbove, 1.0};
    out[1] = {n + kVolumeAbove, v};
    return 2;
  }
  if (a <= -2) {
    out[0] = {n + kVolumeBelow, v};
    return 1;
  }
  SplitRow rows[3];
  const int k = split_rows(g, a, rows);
  for (int i = 0; i < k; ++i) out[i] = {rows[i].row, rows[i].d_number + rows[i].d_volume * v};
  return k;
}

}  // namespace granuflow::kernels
