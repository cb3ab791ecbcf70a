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
  // The longest run of partners k ending at the top class whose aggregates stay in cell k.
  run_first_.assign(n, 0), run_last_.assign(n, -1);
  size_t row = 0;
  for (int j = 0; j < n; row += n - j, ++j) {
    int k = n - 1;
    while (k >= j && cell_[row + (k - j)] == k) --k;
    if (k < n - 1) run_first_[j] = k + 1, run_last_[j] = n - 1;
  }
  diagonals_.clear();
  auto pair = [n](int j, int k) { return pair_index(j, k, n); };
  for (int d = 0; d < n; ++d) {
    if (run_first_[0] <= d && d <= run_last_[0]) break;  // the runs start here
    Diagonal g{cell_[pair(0, d)] - d, d - 1};
    for (int k = d; k < n; ++k) {
      const int j = k - d;
      const bool in_run = run_first_[j] <= k && k <= run_last_[j];
      if (in_run || cell_[pair(j, k)] != k + g.shift || k + g.shift >= n) break;
      g.last = k;
    }
    diagonals_.push_back(g);
  }
}

}  // namespace granuflow::kernels
