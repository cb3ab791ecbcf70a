#include "discretization/cell_average.hpp"

namespace granuflow::kernels {

void CellAverageAggregation::setup(const Grid& g) {
  grid_ = &g;
  n_ = g.size();
  cell_.clear(), vsum_.clear();
  for (int j = 0; j < n_; ++j)
    for (int k = j; k < n_; ++k) {
      const double v = g.pivot(j) + g.pivot(k);
      cell_.push_back(g.cell_of(v));  // >= 0: v > 2 x_0 > e_0
      vsum_.push_back(v);
    }
}

void CellAverageAggregation::add_jacobian(const double* N, const double* beta, double* J) const {
  const int n = n_;
  // Packets (B, V) and their derivatives dB_c/dN_l, dV_c/dN_l, (n + 1) x n.
  std::vector<double> B(n + 1, 0.0), V(n + 1, 0.0);
  db_.assign(size_t(n + 1) * n, 0.0);
  dv_.assign(size_t(n + 1) * n, 0.0);
  for_each_event_jacobian(n, N, beta, J, [&](size_t p, int j, int k, double dj, double dk) {
    const int c = cell_[p];
    const double h = j == k ? 0.5 : 1.0;  // r = h beta N_j N_k
    B[c] += h * dj * N[j];
    V[c] += h * vsum_[p] * dj * N[j];
    double* dbc = &db_[size_t(c) * n];
    double* dvc = &dv_[size_t(c) * n];
    dbc[j] += dj, dbc[k] += dk;
    dvc[j] += vsum_[p] * dj, dvc[k] += vsum_[p] * dk;
  });
  SplitRow rows[3];
  for (int c = 0; c < n; ++c) {
    const int m = split_rows(*grid_, side(c, B[c], V[c]), rows);
    const double* dbc = &db_[size_t(c) * n];
    const double* dvc = &dv_[size_t(c) * n];
    for (int r = 0; r < m; ++r) {
      double* jr = J + size_t(rows[r].row) * n;
      for (int l = 0; l < n; ++l) jr[l] += rows[r].d_number * dbc[l] + rows[r].d_volume * dvc[l];
    }
  }
  for (int l = 0; l < n; ++l) {
    J[size_t(n + kNumberAbove) * n + l] += db_[size_t(n) * n + l];
    J[size_t(n + kVolumeAbove) * n + l] += dv_[size_t(n) * n + l];
  }
}

}  // namespace granuflow::kernels
