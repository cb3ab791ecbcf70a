#include "discretization/fixed_pivot.hpp"

namespace granuflow::kernels {

void FixedPivotAggregation::setup(const Grid& g) {
  const int n = g.size();
  targets_.clear(), vsum_.clear();
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k) {
      const double v = g.pivot(j) + g.pivot(k);
      const int a = g.interval_of(v);  // >= 0: v > 2 x_0 > x_0
      Target t{-1, -1, 0.0, 0.0, 0.0, 0.0};
      if (a >= n) {  // beyond the virtual pivot: leaves whole
        t.w_hi = 1.0, t.f_hi = 1.0;
      } else {
        const double xa = g.pivot_ext(a), xb = g.pivot_ext(a + 1);
        const double nu = (v - xa) / (xb - xa);  // Kumar & Ramkrishna 1996, Eq. (9)
        t.lo = a, t.w_lo = 1.0 - nu, t.f_lo = (1.0 - nu) * xa / v;
        t.hi = a + 1 < n ? a + 1 : -1, t.w_hi = nu, t.f_hi = nu * xb / v;
      }
      targets_.push_back(t);
      vsum_.push_back(v);
    }
}

}  // namespace granuflow::kernels
