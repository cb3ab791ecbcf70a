// Numerical schemes for aggregation: where the aggregate of every pair of classes lands on the grid. The population
// engine (kernels/population/population.hpp) loops over the pairs j <= k (numbered along the row-major upper
// triangle), forms the event rates r = 1/2 beta_jj N_j^2 or beta_jk N_j N_k (paper 001, Eqs. (21), (24)), removes the
// partners and places the aggregates through the scheme, keeping number and volume in the discrete equations
//     number:  sum_i dN_i/dt + d(number_above)/dt = -1/2 sum_{j,k} beta_jk N_j N_k   (one particle per event)
//     volume:  sum_i x_i dN_i/dt + d(volume_above)/dt = 0
// (docs/verification.md "Conservation"). Two schemes are registered: fixed_pivot (Kumar & Ramkrishna 1996) and
// cell_average (Kumar et al. 2006). Extensive properties carried by the particles (water, liquid volume ...) go
// where the aggregate's volume goes, in the same fractions, so they are conserved exactly too.
#pragma once
#include <string>
#include <vector>

#include "discretization/grid.hpp"

namespace granuflow::kernels {

class AggregationScheme {
 public:
  virtual ~AggregationScheme() = default;
  virtual std::string name() const = 0;
  virtual void setup(const Grid& g) = 0;
};

// Pair-index arithmetic of the upper triangle j <= k, row-major.
inline size_t pair_count(int n) { return size_t(n) * (n + 1) / 2; }
inline size_t pair_index(int j, int k, int n) { return size_t(j) * n - size_t(j) * (j - 1) / 2 + (k - j); }

}  // namespace granuflow::kernels
