#include "discretization/fixed_pivot.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

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
namespace {

// One row of the pair triangle with P properties (a compile-time P unrolls the property loops). Every value read is
// first copied to a local: the stores into D could alias the inputs, pi and the tables in the compiler's eyes, which
// otherwise reloads them after each store. The terms and their order per entry of D are those of
// PopulationJacobian::deaths() and the births, unchanged.
template <int kP>
void fixed_pivot_jacobian_row(const FixedPivotAggregation& s, const PopulationJacobian& L, const PairEvent* events,
                              int count) {
  using Target = FixedPivotAggregation::Target;
  const int n = L.n, P = kP >= 0 ? kP : L.P;
  double* const D = L.D;
  const size_t R = L.R;
  const double *pi = L.pi, *dpi_dN = L.dpi_dN, *dpi_dq = L.dpi_dq;
  double local[3 * (kP > 0 ? kP : 1)];
  std::vector<double> heap;
  double* buf = local;
  if (kP < 0) heap.resize(3 * size_t(std::max(P, 1))), buf = heap.data();
  double *pij = buf, *pik = buf + std::max(P, 1), *carried = buf + 2 * std::max(P, 1);
  for (const PairEvent* e = events; e != events + count; ++e) {
    const int j = e->j, k = e->k;
    const double rate = e->rate;
    const Target t = s.target(e->pr);
    const double vol = s.volume(e->pr);
    for (int p = 0; p < P; ++p) {
      pij[p] = pi[size_t(p) * n + j], pik[p] = pi[size_t(p) * n + k];
      carried[p] = pij[p] + pik[p];
    }
    // the partners' deaths (PopulationJacobian::deaths)
    {
      e->for_inputs([&](const PairEvent::Input& in) {
        const double d = in.d;
        double* col = D + size_t(in.col) * R;
        col[L.rowN(j)] += -d;
        col[L.rowN(k)] += -d;
        for (int p = 0; p < P; ++p) {
          col[L.rowQ(p, j)] += -d * pij[p];
          col[L.rowQ(p, k)] += -d * pik[p];
        }
      });
      for (int p = 0; p < P; ++p)
        for (int i : {j, k}) {
          const double dN = dpi_dN[size_t(p) * n + i], dq = dpi_dq[size_t(p) * n + i];
          D[size_t(i) * R + L.rowQ(p, i)] += -rate * dN;
          D[size_t(L.colQ(p, i)) * R + L.rowQ(p, i)] += -rate * dq;
        }
    }
    struct Dest {
      int cls;  // -1: above
      double w, f;
    };
    const Dest dests[2] = {{t.lo, t.w_lo, t.f_lo}, {t.hi, t.w_hi, t.f_hi}};
    for (const Dest& dst : dests) {
      if (dst.w == 0.0 && dst.f == 0.0) continue;
      const double w = dst.w, f = dst.f, fv = f * vol;
      const bool inside = dst.cls >= 0;
      const size_t rowN = inside ? L.rowN(dst.cls) : L.rowO(kOutNumberAbove);
      e->for_inputs([&](const PairEvent::Input& in) {
        const double d = in.d;
        double* col = D + size_t(in.col) * R;
        col[rowN] += w * d;
        if (!inside) col[L.rowO(kOutVolumeAbove)] += fv * d;
        for (int p = 0; p < P; ++p)
          col[inside ? L.rowQ(p, dst.cls) : L.rowO(out_property_above(p))] += f * carried[p] * d;
      });
      for (int p = 0; p < P; ++p) {
        const size_t row = inside ? L.rowQ(p, dst.cls) : L.rowO(out_property_above(p));
        for (int i : {j, k}) {
          const double dN = dpi_dN[size_t(p) * n + i], dq = dpi_dq[size_t(p) * n + i];
          D[size_t(i) * R + row] += f * rate * dN;
          D[size_t(L.colQ(p, i)) * R + row] += f * rate * dq;
        }
      }
    }
  }
}

}  // namespace

// An aggregate stays in the larger partner's class k when its volume falls between x_k and x_{k+1} (lo = k, Kumar &
// Ramkrishna 1996, Eq. (9)); hi is never k. What leaves the grid (hi = -1) is reported for the engine's fold.
bool FixedPivotAggregation::local_births(std::vector<LocalBirths>& per_pair) const {
  per_pair.assign(targets_.size(), {});
  size_t pr = 0;
  const int n = static_cast<int>(run_first_.size());
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k, ++pr) {
      const Target& t = targets_[pr];
      if (t.lo == k) per_pair[pr].stay = t.w_lo, per_pair[pr].stay_share = t.f_lo;
      if (t.hi < 0) per_pair[pr].out_volume = t.f_hi * vsum_[pr], per_pair[pr].out_share = t.f_hi;
    }
  return true;
}

void FixedPivotAggregation::jacobian_row(Tables&, const PopulationJacobian& J, const PairEvent* events,
                                         int count) const {
  switch (J.P) {
    case 0:
      return fixed_pivot_jacobian_row<0>(*this, J, events, count);
    case 1:
      return fixed_pivot_jacobian_row<1>(*this, J, events, count);
    default:
      return fixed_pivot_jacobian_row<-1>(*this, J, events, count);
  }
}

}  // namespace granuflow::kernels
