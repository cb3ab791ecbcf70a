// Fixed pivot technique (Kumar & Ramkrishna 1996, Chem. Eng. Sci. 51, Eqs. (9)-(10)) for aggregation: each
// aggregate of volume x_j + x_k is split between the two pivots around it so that number and volume are kept.
// The split fractions depend on the grid only, so they are tabulated once per pair in setup().
#pragma once
#include "discretization/aggregation_scheme.hpp"

namespace granuflow::kernels {

class FixedPivotAggregation : public AggregationSchemeT<FixedPivotAggregation> {
 public:
  void setup(const Grid& g) override;
  void add_jacobian(const double* N, const double* beta, double* J) const override;

  template <class T>
  void rates(const T* N, const T* beta, T* out) const {
    for_each_event(n_, N, beta, out, [&](size_t p, const T& r) { scatter(p, r, out); });
  }

 private:
  template <class T>
  void scatter(size_t p, const T& r, T* out) const {
    if (lower_[p] >= 0) {
      out[lower_[p]] += w_lower_[p] * r;
      out[lower_[p] + 1] += w_upper_[p] * r;
    } else {
      for (const Weight& w : edge_[-lower_[p] - 1].w)
        if (w.row >= 0) out[w.row] += w.w * r;
    }
  }
  struct EdgePair {
    Weight w[3];
  };
  int n_ = 0;
  std::vector<int> lower_;  // per pair j <= k (row-major upper triangle): lower pivot, or -(edge index + 1)
  std::vector<double> w_lower_, w_upper_;
  std::vector<EdgePair> edge_;  // pairs that reach the top (rows n + kNumberAbove ...)
};

}  // namespace granuflow::kernels
