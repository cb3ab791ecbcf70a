#include "discretization/cell_average.hpp"

namespace granuflow::kernels {

void CellAverageAggregation::setup(const Grid& g) {
  const int n = g.size();
  cell_.clear(), vsum_.clear();
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k) {
      const double v = g.pivot(j) + g.pivot(k);
      cell_.push_back(g.cell_of(v));  // >= 0: v > 2 x_0 > e_0
      vsum_.push_back(v);
    }
}

}  // namespace granuflow::kernels
