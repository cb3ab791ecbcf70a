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
  build_run_layout(*this, g, layout_);
}

// The Jacobian follows the rates: the events first summed into packets (B, V, Q per cell, and their derivatives
// dB, dV, dQ against every input column), then each packet split, which is linear in (B, V) for a given side.
void CellAverageAggregation::jacobian_start(Tables& tables, const PopulationJacobian& J) const {
  auto& t = static_cast<RunTables&>(tables);
  const int n = J.n, P = J.P, C = J.C;
  t.dB.assign(size_t(n + 1) * C, 0.0);
  t.dV.assign(size_t(n + 1) * C, 0.0);
  t.dQ.assign(size_t(P) * (n + 1) * C, 0.0);
  t.jB.assign(n + 1, 0.0), t.jV.assign(n + 1, 0.0), t.jQ.assign(size_t(P) * (n + 1), 0.0);
}

void CellAverageAggregation::jacobian_row(Tables& tables, const PopulationJacobian& J, const PairEvent* events,
                                          int count) const {
  auto& t = static_cast<RunTables&>(tables);
  const int n = J.n, P = J.P, C = J.C;
  const double* pi = J.pi;
  for (const PairEvent* ev = events; ev != events + count; ++ev) {
    const PairEvent& e = *ev;
    J.deaths(e);
    const int c = cell(e.pr);
    const double v = volume(e.pr), rate = e.rate;
    t.jB[c] += rate;
    t.jV[c] += v * rate;
    double* db = &t.dB[size_t(c) * C];
    double* dv = &t.dV[size_t(c) * C];
    e.for_inputs([&](const PairEvent::Input& in) { db[in.col] += in.d, dv[in.col] += v * in.d; });
    for (int p = 0; p < P; ++p) {
      const double carried = pi[size_t(p) * n + e.j] + pi[size_t(p) * n + e.k];
      t.jQ[size_t(p) * (n + 1) + c] += rate * carried;
      double* dqc = &t.dQ[(size_t(p) * (n + 1) + c) * C];
      e.for_inputs([&](const PairEvent::Input& in) { dqc[in.col] += carried * in.d; });
      for (int i : {e.j, e.k}) {
        dqc[i] += rate * J.dpi_dN[size_t(p) * n + i];
        dqc[J.colQ(p, i)] += rate * J.dpi_dq[size_t(p) * n + i];
      }
    }
  }
}

void CellAverageAggregation::jacobian_finish(Tables& tables, const PopulationJacobian& J) const {
  auto& t = static_cast<RunTables&>(tables);
  const int n = J.n, P = J.P, C = J.C;
  const Grid& g = *J.grid;
  const auto& x = g.pivots();
  const std::vector<double>&B = t.jB, &V = t.jV, &Q = t.jQ;
  SplitRow rows[3];
  for (int c = 0; c <= n; ++c) {
    const double* db = &t.dB[size_t(c) * C];
    const double* dv = &t.dV[size_t(c) * C];
    if (c == n) {  // beyond the top edge: leaves whole
      for (int col = 0; col < C; ++col) {
        J.add(J.rowO(kOutNumberAbove), col, db[col]);
        J.add(J.rowO(kOutVolumeAbove), col, dv[col]);
        for (int p = 0; p < P; ++p)
          J.add(J.rowO(out_property_above(p)), col, t.dQ[(size_t(p) * (n + 1) + n) * C + col]);
      }
      continue;
    }
    const int m = split_rows(g, side(g, c, B[c], V[c]), rows);
    for (int r = 0; r < m; ++r) {
      const size_t row = rows[r].row < n ? J.rowN(rows[r].row) : J.rowO(rows[r].row - n);
      for (int col = 0; col < C; ++col)
        if (db[col] != 0.0 || dv[col] != 0.0) J.add(row, col, rows[r].d_number * db[col] + rows[r].d_volume * dv[col]);
    }
    if (P == 0 || V[c] == 0.0) continue;
    // Property share of a placement: Q vol / V with vol = X (d_number B + d_volume V) linear in (B, V).
    for (int r = 0; r < m; ++r) {
      const int rr = rows[r].row;
      if (rr == n + kNumberAbove) continue;   // a number row; its volume row carries the property
      const double X = rr < n ? x[rr] : 1.0;  // outside rows already count volume
      const double vol = X * (rows[r].d_number * B[c] + rows[r].d_volume * V[c]);
      for (int p = 0; p < P; ++p) {
        const double Qc = Q[size_t(p) * (n + 1) + c];
        const double* dqc = &t.dQ[(size_t(p) * (n + 1) + c) * C];
        const size_t row = rr < n                   ? J.rowQ(p, rr)
                           : rr == n + kVolumeAbove ? J.rowO(out_property_above(p))
                                                    : J.rowO(out_property_below(p));
        for (int col = 0; col < C; ++col) {
          const double dvol = X * (rows[r].d_number * db[col] + rows[r].d_volume * dv[col]);
          const double d = (vol * dqc[col] + Qc * dvol) / V[c] - Qc * vol * dv[col] / (V[c] * V[c]);
          if (d != 0.0) J.add(row, col, d);
        }
      }
    }
  }
}

}  // namespace granuflow::kernels
