#include "discretization/fixed_pivot.hpp"

#include <cmath>

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
      w_lo_.push_back(t.w_lo), w_hi_.push_back(t.w_hi), f_lo_.push_back(t.f_lo), f_hi_.push_back(t.f_hi);
    }
  // The longest run of partners k ending at n - 2 whose aggregates land on k and k + 1.
  run_first_.assign(n, 0), run_last_.assign(n, -1);
  size_t row = 0;
  for (int j = 0; j < n; row += n - j, ++j) {
    int k = n - 2;
    while (k >= j && targets_[row + (k - j)].lo == k && targets_[row + (k - j)].hi == k + 1) --k;
    if (k < n - 2) run_first_[j] = k + 1, run_last_[j] = n - 2;
  }
  // Off the runs the weight arrays hold 0: a row's rates, deaths and run births are then one loop over all partners,
  // the births of the pairs off the run placed through target().
  row = 0;
  for (int j = 0; j < n; row += n - j, ++j)
    for (int k = j; k < n; ++k)
      if (k < run_first_[j] || k > run_last_[j]) {
        const size_t pr = row + (k - j);
        w_lo_[pr] = w_hi_[pr] = f_lo_[pr] = f_hi_[pr] = 0.0;
      }
  // Diagonals below the runs: shift and weights of the first pair, kept while every pair along it agrees.
  diagonals_.clear();
  auto pair = [n](int j, int k) { return pair_index(j, k, n); };
  for (int d = 0; d < n; ++d) {
    const Target& t0 = targets_[pair(0, d)];
    if (run_first_[0] <= d && d <= run_last_[0]) break;  // the runs start here
    Diagonal g{t0.lo - d, d - 1, t0.w_lo, t0.w_hi, t0.f_lo, t0.f_hi};
    for (int k = d; k < n; ++k) {
      const int j = k - d;
      const Target& t = targets_[pair(j, k)];
      const bool in_run = run_first_[j] <= k && k <= run_last_[j];
      if (in_run || t.lo != k + g.shift || t.hi != k + g.shift + 1 || std::abs(t.w_lo - g.w_lo) > 1e-12 ||
          std::abs(t.w_hi - g.w_hi) > 1e-12 || std::abs(t.f_lo - g.f_lo) > 1e-12 || std::abs(t.f_hi - g.f_hi) > 1e-12)
        break;
      g.last = k;
    }
    diagonals_.push_back(g);
  }
  build_run_layout(*this, g, layout_);
}

// The aggregate's share on each target (Kumar & Ramkrishna 1996, Eq. (9)): number w times the event rate, property
// f times what the partners carry, both linear in the rate and in the partners' per-particle properties.

void FixedPivotAggregation::jacobian_row(Tables&, const PopulationJacobian& J, const PairEvent* events,
                                         int count) const {
  // J and its fields as locals: invariant across the pairs and the stores into D.
  const PopulationJacobian L = J;
  const int n = L.n, P = L.P;
  double* const D = L.D;
  const size_t R = L.R;
  const double *pi = L.pi, *dpi_dN = L.dpi_dN, *dpi_dq = L.dpi_dq;
  auto add = [D, R](size_t r, int c, double v) { D[size_t(c) * R + r] += v; };
  struct Dest {
    int cls;  // -1: above
    double w, f;
  };
  for (const PairEvent* e = events; e != events + count; ++e) {
    L.deaths(*e);
    const int j = e->j, k = e->k;
    const Target& t = target(e->pr);
    const Dest dests[2] = {{t.lo, t.w_lo, t.f_lo}, {t.hi, t.w_hi, t.f_hi}};
    for (const Dest& d : dests) {
      if (d.w == 0.0 && d.f == 0.0) continue;
      e->for_inputs([&](const PairEvent::Input& in) {
        if (d.cls >= 0) {
          add(L.rowN(d.cls), in.col, d.w * in.d);
        } else {
          add(L.rowO(kOutNumberAbove), in.col, d.w * in.d);
          add(L.rowO(kOutVolumeAbove), in.col, d.f * volume(e->pr) * in.d);
        }
        for (int p = 0; p < P; ++p) {
          const double carried = pi[size_t(p) * n + j] + pi[size_t(p) * n + k];
          add(d.cls >= 0 ? L.rowQ(p, d.cls) : L.rowO(out_property_above(p)), in.col, d.f * carried * in.d);
        }
      });
      for (int p = 0; p < P; ++p) {
        const size_t row = d.cls >= 0 ? L.rowQ(p, d.cls) : L.rowO(out_property_above(p));
        for (int i : {j, k}) {
          add(row, i, d.f * e->rate * dpi_dN[size_t(p) * n + i]);
          add(row, L.colQ(p, i), d.f * e->rate * dpi_dq[size_t(p) * n + i]);
        }
      }
    }
  }
}

}  // namespace granuflow::kernels
