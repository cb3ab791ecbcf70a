// The grid of the two-dimensional population balance over solid volume s and liquid volume l (paper 002,
// Eqs. (6)-(10)): the tensor product of a solid grid (any Grid, geometric in volume in the scenes; the fixed-pivot
// split of aggregates works on it exactly as in one dimension) and a uniform liquid grid with pivots
// l_j = j dl, j = 0 .. nl - 1, that starts at l = 0 (dry particles are a class of their own).
//
// Why liquid volume and not liquid content as the second coordinate: liquid volume is additive, so an aggregate of
// bins (i, j) and (k, m) has liquid exactly l_j + l_m = l_{j+m}, a pivot of the same grid. Aggregation then needs
// no split in the liquid direction (no numerical spreading of the liquid content), conserves liquid volume exactly
// with the number, and the liquid direction of the birth term is a discrete convolution, evaluated by FFT
// (population2d.hpp). A liquid-content grid would need every aggregate's content (a solid-weighted mean of the
// partners') split between two content pivots and the O(n^4) pair loop. The price: the liquid axis spans a fixed
// volume nl dl; what grows beyond it leaves the grid and is counted (docs/pbm_2d.md).
//
// Bins are numbered a = i * nl + j (solid class i, liquid class j). The liquid content of a bin, Eq. (13) and
// (16) of paper 002, is l_j / (s_i + l_j) at its pivot, its diameter (6 (s_i + l_j) / pi)^(1/3) (Eq. (15)).
#pragma once
#include <memory>

#include "discretization/grid.hpp"

namespace granuflow::kernels {

class Grid2D {
 public:
  // `liquid_classes` >= 2 pivots spaced `liquid_step` (m^3) from 0.
  Grid2D(std::shared_ptr<const Grid> solid, int liquid_classes, double liquid_step);

  const Grid& solid() const { return *solid_; }
  std::shared_ptr<const Grid> solid_ptr() const { return solid_; }
  int ns() const { return solid_->size(); }
  int nl() const { return nl_; }
  int size() const { return ns() * nl_; }
  int bin(int i, int j) const { return i * nl_ + j; }
  double liquid_step() const { return dl_; }  // m^3
  double liquid(int j) const { return j * dl_; }
  double solid_volume(int a) const { return solid_->pivot(a / nl_); }
  double liquid_volume(int a) const { return liquid(a % nl_); }
  double total_volume(int a) const { return solid_volume(a) + liquid_volume(a); }
  double liquid_content(int a) const { return liquid_volume(a) / total_volume(a); }
  double diameter(int a) const { return diameter_of_volume(total_volume(a)); }
  // Per bin, in bin order.
  const std::vector<double>& total_volumes() const { return volume_; }
  const std::vector<double>& diameters() const { return diameter_; }
  const std::vector<double>& liquid_contents() const { return content_; }

  // A particle that gains (or loses) liquid volume dv from liquid class j: its new liquid volume l_j + dv split
  // between the liquid pivots below and above so that number and liquid volume are kept. lo >= 0; a class index
  // >= nl is beyond the grid (the caller counts it outside with liquid volume index * dl).
  struct LiquidSplit {
    int lo, hi;
    double w_lo, w_hi;
  };
  LiquidSplit shift(int j, double dv) const;

 private:
  std::shared_ptr<const Grid> solid_;
  int nl_;
  double dl_;
  std::vector<double> volume_, diameter_, content_;
};

}  // namespace granuflow::kernels
