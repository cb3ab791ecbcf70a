#include "discretization/fixed_pivot.hpp"

namespace granuflow::kernels {

void FixedPivotAggregation::setup(const Grid& g) {
  n_ = g.size();
  lower_.clear(), w_lower_.clear(), w_upper_.clear(), edge_.clear();
  for (int j = 0; j < n_; ++j)
    for (int k = j; k < n_; ++k) {
      Weight w[3];
      const int m = place_particle(g, g.pivot(j) + g.pivot(k), w);
      if (m == 2 && w[0].row < n_ && w[1].row == w[0].row + 1) {
        lower_.push_back(w[0].row), w_lower_.push_back(w[0].w), w_upper_.push_back(w[1].w);
      } else {
        EdgePair e;
        for (int i = 0; i < 3; ++i) e.w[i] = i < m ? w[i] : Weight{-1, 0.0};
        edge_.push_back(e);
        lower_.push_back(-static_cast<int>(edge_.size())), w_lower_.push_back(0), w_upper_.push_back(0);
      }
    }
}

void FixedPivotAggregation::add_jacobian(const double* N, const double* beta, double* J) const {
  const int n = n_;
  auto add_birth = [&](size_t p, int col, double d) {
    if (lower_[p] >= 0) {
      J[size_t(lower_[p]) * n + col] += w_lower_[p] * d;
      J[size_t(lower_[p] + 1) * n + col] += w_upper_[p] * d;
    } else {
      for (const Weight& w : edge_[-lower_[p] - 1].w)
        if (w.row >= 0) J[size_t(w.row) * n + col] += w.w * d;
    }
  };
  for_each_event_jacobian(n, N, beta, J, [&](size_t p, int j, int k, double dj, double dk) {
    add_birth(p, j, dj);
    if (k != j) add_birth(p, k, dk);
  });
}

}  // namespace granuflow::kernels
