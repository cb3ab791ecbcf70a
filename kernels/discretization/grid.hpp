// The size grid of the population balance: n classes with edges e_0 < e_1 < ... < e_n and one pivot x_i inside
// each cell (e_i, e_{i+1}), in particle volume (m^3); diameters are those of volume-equivalent spheres,
// d = (6 v / pi)^(1/3).
//
//  * geometric(v_min, q, n): e_i = v_min r^i with r = 2^(1/q) (Kumar & Ramkrishna 1996), pivots at the cell
//    midpoints in volume x_i = (e_i + e_{i+1}) / 2 (the cell average technique's choice, Kumar et al. 2006);
//  * from_edges(e): any increasing edges, pivots at the volume midpoints;
//  * from_pivots(x): given pivots (paper 001: 10 log-spaced pivots from 50 to 1000 um), edges at the geometric
//    means of neighbouring pivots and, outside, at the same ratio.
//
// Two virtual pivots continue the grid: x_lo = x_0^2 / x_1 below and x_hi = x_{n-1}^2 / x_{n-2} above. The
// moment-preserving redistribution sends what would land on them out of the grid, where the unit tracks it.
#pragma once
#include <vector>

namespace granuflow::kernels {

class Grid {
 public:
  static Grid geometric(double v_min, int q, int classes);
  static Grid from_edges(std::vector<double> volume_edges);
  static Grid from_pivots(std::vector<double> volume_pivots);
  static Grid from_diameter_pivots(const std::vector<double>& diameter_pivots);

  int size() const { return static_cast<int>(pivots_.size()); }
  const std::vector<double>& edges() const { return edges_; }               // m^3, n + 1
  const std::vector<double>& pivots() const { return pivots_; }             // m^3, n
  const std::vector<double>& diameter_edges() const { return d_edges_; }    // m
  const std::vector<double>& diameter_pivots() const { return d_pivots_; }  // m
  double edge(int i) const { return edges_[i]; }
  double pivot(int i) const { return pivots_[i]; }
  double width(int i) const { return edges_[i + 1] - edges_[i]; }
  double lower_virtual() const { return x_lo_; }
  double upper_virtual() const { return x_hi_; }
  // Pivot i for -1 <= i <= n, with the virtual pivots at -1 and n.
  double pivot_ext(int i) const { return i < 0 ? x_lo_ : i >= size() ? x_hi_ : pivots_[i]; }
  // Cell holding volume v: -1 below e_0, n at or above e_n.
  int cell_of(double v) const;
  // Pivot interval [x_a, x_{a+1}] holding v, -1 <= a <= n - 1 (extended pivots); -2 below x_lo, n above x_hi.
  int interval_of(double v) const;

 private:
  Grid(std::vector<double> edges, std::vector<double> pivots);
  std::vector<double> edges_, pivots_, d_edges_, d_pivots_;
  double x_lo_ = 0, x_hi_ = 0;
};

double diameter_of_volume(double v);
double volume_of_diameter(double d);

}  // namespace granuflow::kernels
