// The population engine's Jacobian: analytic for everything built in (the kernels' derivatives from small forward-AD
// evaluations per class and per pair; the aggregation scheme places the births, discretization/aggregation_scheme.hpp),
// forward AD over the engine's inputs where no analytic path exists; folded, then mapped to the unit's rows and
// columns.
#include <algorithm>
#include <utility>

#include "population/population_work.hpp"

namespace granuflow::kernels {

void Population::fold_rows(double* D, int cols) const {
  if (outside_ != Outside::kFold) return;
  const int n = n_, P = properties();
  const auto& x = grid_->pivots();
  const size_t out0 = size_t(n) * (1 + P), R = jacobian_rows();
  for (int c = 0; c < cols; ++c) {
    double* col = D + size_t(c) * R;
    col[0] += col[out0 + kOutVolumeBelow] / x[0];
    col[n - 1] += col[out0 + kOutVolumeAbove] / x[n - 1];
    for (int p = 0; p < P; ++p) {
      col[size_t(n) * (1 + p)] += col[out0 + out_property_below(p)];
      col[size_t(n) * (1 + p) + n - 1] += col[out0 + out_property_above(p)];
    }
  }
}

void Population::jacobian(Work& w, const State<double>& s, const Map& m, JacobianSink& sink) const {
  const FlushDenormals ftz;
  refresh(w, s.p);
  const int n = n_, P = properties(), no = outside_rows(), C = input_cols(), R = jacobian_rows();
  w.D.assign(size_t(R) * C, 0.0);
  const bool ad = needs_.number || (sel_.kernel && sel_.kernel->state_dependent());
  // A class-local Newton matrix reads only the entries within one class: the analytic path then forms only those,
  // where the aggregation scheme can say which births stay in a class, no row outside the grid is a state and what
  // leaves the grid is folded back (then the pair terms conserve what they move, and what is left out of a column
  // sums to minus what is kept: JacobianSink::left_out).
  const bool local = sink.classes_local() && !ad && m.outside_row.empty() && outside_ == Outside::kFold &&
                     (!agg_.kernel || local_births_known(w));
  if (ad)
    ad_jacobian(w, s, w.D);
  else
    analytic_jacobian(w, s, w.D, local);
  fold_rows(w.D.data(), C);
  // Map the engine's rows and inputs to the unit's (row, factor) and (column, scale).
  std::vector<int>& rows = w.map_rows;
  std::vector<int>& cols = w.map_cols;
  std::vector<double>& factors = w.map_factors;
  std::vector<double>& scales = w.map_scales;
  rows.assign(R, -1), factors.assign(R, 0.0), cols.assign(C, -1), scales.assign(C, 1.0);
  for (int i = 0; i < n; ++i) rows[i] = m.N_row[i], factors[i] = m.N_factor[i];
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) rows[n * (1 + p) + i] = m.q_row[p][i], factors[n * (1 + p) + i] = m.q_factor;
  for (int k = 0; k < no && k < static_cast<int>(m.outside_row.size()); ++k)
    rows[n * (1 + P) + k] = m.outside_row[k], factors[n * (1 + P) + k] = -1.0;
  rows[R - 1] = m.grown_row, factors[R - 1] = -1.0;
  for (int i = 0; i < n; ++i) cols[i] = m.N_col[i], scales[i] = m.N_scale[i];
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) cols[n * (1 + p) + i] = m.q_col[p][i];
  for (size_t fi = 0; fi < field_index_.size(); ++fi) {
    const std::vector<int>& fc = m.field_col[field_index_[fi]];
    for (int i = 0; i < n && !fc.empty(); ++i) cols[n * (1 + P) + static_cast<int>(fi) * n + i] = fc[i];
  }
  if (local) {  // each column's own class rows, the rows outside the grid and of the growth volume
    const int inner = n * (1 + P);
    for (int c = 0; c < C; ++c) {
      if (cols[c] < 0) continue;
      const int cls = c < inner ? c % n : (c - inner) % n;
      const double* d = &w.D[size_t(c) * R];
      auto put = [&](int r) {
        if (rows[r] >= 0 && d[r] != 0.0) sink.add(rows[r], cols[c], factors[r] * d[r] * scales[c]);
      };
      for (int q = 0; q <= P; ++q) put(q * n + cls);
      for (int r = inner; r < R; ++r) put(r);
      // the pair terms conserve numbers' mass and the properties: a column's left-out entries in a class block sum
      // to minus what it kept there (the fields' columns kept none)
      for (int q = 0; q <= P && c < inner; ++q) {
        const int r = q * n + cls;
        const double kept = w.local_kept[size_t(q) * inner + c];
        if (rows[r] >= 0 && kept != 0.0) sink.left_out(rows[r], cols[c], -factors[r] * kept * scales[c]);
      }
    }
    return;
  }
  // The engine's rows that land on consecutive unit rows (each class's number, each property), mapped as runs: a
  // dense column then takes each run as one vector update instead of a test and an indexed add per entry (the mapping
  // was 12 % of the Jacobian at 80 classes). A zero of D adds a zero, which leaves every entry's value as it was.
  std::vector<Work::RowRun>& runs = w.map_runs;
  runs.clear();
  for (int r = 0; r < R; ++r) {
    if (rows[r] < 0) continue;
    if (!runs.empty() && runs.back().first + runs.back().len == r && runs.back().row + runs.back().len == rows[r])
      ++runs.back().len;
    else
      runs.push_back({r, 1, rows[r]});
  }
  // Column by column (D is column-major), so that a dense sink's column (the unit's rows, mostly consecutive) is
  // written in order. Each sink entry receives its terms in the same order as row by row (several engine columns can
  // map to one sink column: the temperature field).
  for (int c = 0; c < C; ++c) {
    if (cols[c] < 0) continue;
    const double* d = &w.D[size_t(c) * R];
    const double sc = scales[c];
    if (double* col = sink.dense_column(cols[c])) {
      for (const Work::RowRun& run : runs) {
        const double* dr = d + run.first;
        const double* fr = factors.data() + run.first;
        double* to = col + run.row;
        const int len = run.len;
#pragma omp simd
        for (int t = 0; t < len; ++t) to[t] += fr[t] * dr[t] * sc;
      }
    } else {
      for (int r = 0; r < R; ++r)
        if (d[r] != 0.0 && rows[r] >= 0) sink.add(rows[r], cols[c], factors[r] * d[r] * sc);
    }
  }
}

// d(rates)/d(N, q, fields) of the built-in mechanisms into D (rows: class numbers, properties, outside; columns: N,
// q, the fields read), before folding.
void Population::analytic_jacobian(Work& w, const State<double>& s, std::vector<double>& Dv, bool local) const {
  const int n = n_, P = properties();
  const double* N = s.N;
  // Per-particle properties and their derivatives.
  std::vector<double> pi(size_t(P) * n), dpi_dN(size_t(P) * n), dpi_dq(size_t(P) * n);
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) {
      const double den = N[i] + (s.floor ? s.floor[i] : 0.0);
      pi[size_t(p) * n + i] = s.q[p][i] / den;
      dpi_dq[size_t(p) * n + i] = 1.0 / den;
      dpi_dN[size_t(p) * n + i] = -pi[size_t(p) * n + i] / den;
    }
  const PopulationJacobian J{
      grid_.get(), n, P, input_cols(), size_t(jacobian_rows()), Dv.data(), pi.data(), dpi_dN.data(), dpi_dq.data()};
  if (agg_.kernel && local)
    aggregation_local_jacobian(w, s, J);
  else if (agg_.kernel)
    aggregation_jacobian(w, s, J);
  if (sel_.kernel) breakage_jacobian(w, J, local);
  if (local) {
    const int inner = n * (1 + P);
    const size_t R = J.R;
    w.local_kept.assign(size_t(1 + P) * inner, 0.0);
    for (int c = 0; c < inner; ++c)
      for (int q = 0; q <= P; ++q) w.local_kept[size_t(q) * inner + c] = Dv[size_t(c) * R + size_t(q) * n + c % n];
  }
  if (growth_.kernel) growth_jacobian(w, s, J);
}

// The features phi_i of the aggregation kernel and dphi_i/dfield_i (G, n x mf x fields read): every class's field f
// seeded in direction f at once (phi_i reads class i only).
void Population::feature_gradients(Work& w, const State<double>& s, std::vector<double>& phi,
                                   std::vector<double>& G) const {
  const int n = n_, mf = agg_.kernel->n_features(), nfr = static_cast<int>(field_index_.size());
  const double* kp = s.p + agg_.first;
  w.jf.resize(size_t(kFields) * n);
  ClassState<Jet> cj;
  cj.n = n, cj.volume = grid_->pivots().data(), cj.diameter = grid_->diameter_pivots().data();
  for (int fi = 0; fi < nfr; ++fi) {
    const int f = field_index_[fi];
    for (int i = 0; i < n; ++i) {
      w.jf[size_t(f) * n + i] = Jet(s.fields[f][i]);
      w.jf[size_t(f) * n + i].v[fi] = 1.0;
    }
    cj.fields[f] = &w.jf[size_t(f) * n];
  }
  w.jp.resize(agg_.count);
  for (int k = 0; k < agg_.count; ++k) w.jp[k] = Jet(kp[k]);
  w.jphi.resize(size_t(n) * mf);
  agg_.kernel->features(cj, w.jp.data(), w.jphi.data());
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < mf; ++a) {
      phi[size_t(i) * mf + a] = w.jphi[size_t(i) * mf + a].a;
      for (int fi = 0; fi < nfr; ++fi) G[(size_t(i) * mf + a) * nfr + fi] = w.jphi[size_t(i) * mf + a].v[fi];
    }
}

// Aggregation: per pair, the event rate's derivatives against the inputs it reads (N_j, N_k and the fields of both
// partners through the efficiency); the scheme adds the partners' deaths (PopulationJacobian::deaths) and the births.
void Population::aggregation_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const {
  const int n = n_, P = properties(), nfr = static_cast<int>(field_index_.size());
  const double* kp = s.p + agg_.first;
  const double* N = s.N;
  auto colF = [&](int fi, int i) { return n * (1 + P) + fi * n + i; };
  const int mf = agg_.kernel->n_features();
  std::vector<double> phi(size_t(n) * mf), G(size_t(n) * mf * std::max(nfr, 1), 0.0);
  if (mf > 0) feature_gradients(w, s, phi, G);
  agg_scheme_->jacobian_start(*w.agg, J);
  if (mf > 0) {
    const size_t pairs = size_t(n) * (n + 1) / 2;
    w.eff.resize(pairs), w.eff_da.resize(pairs * mf), w.eff_db.resize(pairs * mf);
    agg_.kernel->efficiency_gradients(phi.data(), n, kp, agg_.count, w.eff.data(), w.eff_da.data(), w.eff_db.data());
  }
  // Per row of the pair triangle, each event's inputs: N_j, N_k and the fields of both partners.
  using In = PairEvent::Input;
  w.inputs.resize(size_t(n) * (2 + 2 * nfr));
  w.events.resize(n);
  size_t pr = 0;
  for (int j = 0; j < n; ++j) {
    In* in = w.inputs.data();
    int count = 0;
    for (int k = j; k < n; ++k, ++pr) {
      const double Kh = w.Kh[pr];
      double E = 1.0;
      const double* dEa = mf > 0 ? &w.eff_da[pr * mf] : nullptr;
      const double* dEb = mf > 0 ? &w.eff_db[pr * mf] : nullptr;
      if (mf > 0) E = w.eff[pr];
      const double beta = Kh * E, rate = beta * N[j] * N[k];
      In* ev_buf = in;
      ev_buf[0] = {j, beta * N[k]};
      ev_buf[1] = {k, beta * N[j]};
      int nev = 2;
      for (int fi = 0; fi < nfr && mf > 0; ++fi) {
        double dj = 0, dk = 0;
        for (int c = 0; c < mf; ++c) {
          dj += dEa[c] * G[(size_t(j) * mf + c) * nfr + fi];
          dk += dEb[c] * G[(size_t(k) * mf + c) * nfr + fi];
        }
        ev_buf[nev++] = {colF(fi, j), Kh * N[j] * N[k] * dj};
        ev_buf[nev++] = {colF(fi, k), Kh * N[j] * N[k] * dk};
      }
      in += nev;
      w.events[count++] = PairEvent{pr, j, k, rate, ev_buf, in};
    }
    agg_scheme_->jacobian_row(*w.agg, J, w.events.data(), count);  // deaths and births, pair by pair
  }
  agg_scheme_->jacobian_finish(*w.agg, J);
}

bool Population::local_births_known(Work& w) const {
  if (w.local_births_state == 0) w.local_births_state = agg_scheme_->local_births(w.local_births) ? 1 : -1;
  return w.local_births_state == 1;
}

// The class-local part of the aggregation Jacobian: each class's own derivatives against its numbers and properties,
// d(rates of class i)/d(N_i, q_i), the entries within one class of aggregation_jacobian's
// (tests/cpp/test_class_local.cpp): each partner's deaths, and the births that stay in the larger partner's class k
// or, folded back into the top class (Outside::kFold), leave the grid above it. A few operations per pair into sums
// per class, instead of a scattered update per entry and input of every pair. The efficiency's derivatives against
// the fields are left out whole: the pair terms conserve what they move, so their column sums over a class block are
// zero with them and without them, and the Newton iteration converged no slower without them (headline scene, 20 to
// 193 classes).
void Population::aggregation_local_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const {
  const int n = n_, P = properties();
  const double* N = s.N;
  const double *pi = J.pi, *dpi_dN = J.dpi_dN, *dpi_dq = J.dpi_dq;
  const double* E = nullptr;
  if (const int mf = agg_.kernel->n_features(); mf > 0) {
    auto& sc = w.sd;
    sc.phi.resize(size_t(n) * mf);
    agg_.kernel->features(class_state(s), s.p + agg_.first, sc.phi.data());
    sc.E.resize(pair_count(n));
    agg_.kernel->efficiencies(sc.phi.data(), n, s.p + agg_.first, sc.E.data());
    E = sc.E.data();
  }
  // Per class: its deaths against its N (dN), the event rate per death (rate, for the per-particle properties'
  // derivatives), and the births that stay in it against its N (bN) and, per property, its q rows (bQN, bQQ).
  const size_t per_p = size_t(P) * n;
  w.local_sums.assign(3 * size_t(n) + 2 * per_p, 0.0);
  double* next = w.local_sums.data();
  auto take = [&next](size_t count) { return std::exchange(next, next + count); };
  double *dN = take(n), *rate = take(n), *bN = take(n), *bQN = take(per_p), *bQQ = take(per_p);
  const double top = grid_->pivots()[n - 1];  // what leaves the grid is folded into the top class (Outside::kFold)
  size_t pr = 0;
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k, ++pr) {
      const double beta = E ? w.Kh[pr] * E[pr] : w.Kh[pr], r = beta * N[j] * N[k];
      const bool like = j == k;  // both partners, and both inputs N, are class j
      if (like) {
        dN[j] += 2.0 * (beta * N[k] + beta * N[j]), rate[j] += 2.0 * r;
      } else {
        dN[j] += beta * N[k], dN[k] += beta * N[j], rate[j] += r, rate[k] += r;
      }
      const AggregationScheme::LocalBirths& b = w.local_births[pr];
      double stay = b.stay, share = b.stay_share;
      if (k == n - 1) stay += b.out_volume / top, share += b.out_share;
      if (stay == 0.0 && share == 0.0) continue;
      const double dk = like ? beta * N[j] + beta * N[k] : beta * N[j];  // the event rate against class k's N
      const double twice = like ? 2.0 : 1.0;                             // partner k's per-particle terms
      bN[k] += stay * dk;
      for (int p = 0; p < P; ++p) {
        const size_t q = size_t(p) * n + k;
        bQN[q] += share * ((pi[size_t(p) * n + j] + pi[q]) * dk + twice * r * dpi_dN[q]);
        bQQ[q] += share * twice * r * dpi_dq[q];
      }
    }
  for (int i = 0; i < n; ++i) {
    J.add(J.rowN(i), i, bN[i] - dN[i]);
    for (int p = 0; p < P; ++p) {
      const size_t q = size_t(p) * n + i;
      J.add(J.rowQ(p, i), i, bQN[q] - dN[i] * pi[q] - rate[i] * dpi_dN[q]);
      J.add(J.rowQ(p, i), J.colQ(p, i), bQQ[q] - rate[i] * dpi_dq[q]);
    }
  }
}

// Growth: the growth scheme's flux Jacobian; properties with the donor cell's particles.
void Population::growth_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const {
  const int n = n_, P = properties();
  const double* N = s.N;
  // J's layout under short names, as the terms below are written
  const double *pi = J.pi, *dpi_dN = J.dpi_dN, *dpi_dq = J.dpi_dq;
  auto rowN = [&](int i) { return J.rowN(i); };
  auto rowQ = [&](int p, int i) { return J.rowQ(p, i); };
  auto rowO = [&](int k) { return J.rowO(k); };
  auto colQ = [&](int p, int i) { return J.colQ(p, i); };
  auto add = [&](size_t r, int c, double v) { J.add(r, c, v); };
  const size_t out0 = size_t(n) * (1 + P);
  const int nf = n + 1;
  auto& sc = w.sd;
  const GrowthTerms<double> g = growth_terms(w, s.p);
  growth_scheme_->fluxes(N, g, sc.F.data(), sc.donor.data());
  w.dF.resize(size_t(nf) * n);
  growth_scheme_->flux_jacobian(N, g, w.dF.data());
  const size_t grown = out0 + outside_rows();
  const auto& dx = growth_scheme_->face_volume_steps();
  for (int f = 0; f < nf; ++f) {
    const double* dF = &w.dF[size_t(f) * n];
    for (int l = 0; l < n; ++l) {
      if (dF[l] == 0.0) continue;
      add(grown, l, dF[l] * dx[f]);
      if (f > 0)
        add(rowN(f - 1), l, -dF[l]);
      else
        add(rowO(kOutVolumeBelow), l, -dF[l] * grid_->lower_virtual());
      if (f < n) {
        add(rowN(f), l, dF[l]);
      } else {
        add(rowO(kOutNumberAbove), l, dF[l]);
        add(rowO(kOutVolumeAbove), l, dF[l] * grid_->upper_virtual());
      }
    }
    const int d = sc.donor[f];
    if (d < 0) continue;
    for (int p = 0; p < P; ++p) {
      const size_t from = f > 0 ? rowQ(p, f - 1) : rowO(out_property_below(p));
      const size_t to = f < n ? rowQ(p, f) : rowO(out_property_above(p));
      const double pid = pi[size_t(p) * n + d];
      // Fq = F pi_d: dFq/dN_l = dF/dN_l pi_d + F dpi_d/dN_d [l = d], dFq/dq_d = F dpi_d/dq_d
      for (int l = 0; l < n; ++l) {
        double v = dF[l] * pid;
        if (l == d) v += sc.F[f] * dpi_dN[size_t(p) * n + d];
        if (v == 0.0) continue;
        add(from, l, -v);
        add(to, l, v);
      }
      const double vq = sc.F[f] * dpi_dq[size_t(p) * n + d];
      add(from, colQ(p, d), -vq);
      add(to, colQ(p, d), vq);
    }
  }
}

// Forward AD over the engine's inputs (N, q, fields), kAdChunk at a time: for kernels that read N.
void Population::ad_jacobian(Work& w, const State<double>& s, std::vector<double>& D) const {
  make_jets(w);
  const int n = n_, P = properties(), no = outside_rows(), C = input_cols(),
            nfr = static_cast<int>(field_index_.size()), R = jacobian_rows();
  int np = 0;
  for (int k : kernel_params_) np = std::max(np, k + 1);
  w.jp.resize(np);
  for (int k : kernel_params_) w.jp[k] = Jet(s.p[k]);
  w.jN.resize(n), w.jq.resize(size_t(P) * n), w.jf.resize(size_t(kFields) * n);
  std::vector<Jet> jfloor(n), dN(n), dq(size_t(P) * n), out(no);
  Jet grown;
  for (int i = 0; i < n; ++i) jfloor[i] = Jet(s.floor ? s.floor[i] : 0.0);
  State<Jet> js;
  js.N = w.jN.data();
  js.floor = jfloor.data();
  js.p = w.jp.data();
  for (int p = 0; p < P; ++p) js.q[p] = &w.jq[size_t(p) * n];
  for (int fi = 0; fi < nfr; ++fi) js.fields[field_index_[fi]] = &w.jf[size_t(field_index_[fi]) * n];
  Rates<Jet> jr;
  jr.dN = dN.data();
  for (int p = 0; p < P; ++p) jr.dq[p] = &dq[size_t(p) * n];
  jr.outside = out.data();
  jr.grown = &grown;
  for (int c0 = 0; c0 < C; c0 += kAdChunk) {
    const int c1 = std::min(C, c0 + kAdChunk);
    for (int i = 0; i < n; ++i) w.jN[i] = Jet(s.N[i]);
    for (int p = 0; p < P; ++p)
      for (int i = 0; i < n; ++i) w.jq[size_t(p) * n + i] = Jet(s.q[p][i]);
    for (int fi = 0; fi < nfr; ++fi)
      for (int i = 0; i < n; ++i) w.jf[size_t(field_index_[fi]) * n + i] = Jet(s.fields[field_index_[fi]][i]);
    for (int c = c0; c < c1; ++c) {
      if (c < n)
        w.jN[c].v[c - c0] = 1.0;
      else if (c < n * (1 + P))
        w.jq[c - n].v[c - c0] = 1.0;
      else
        w.jf[size_t(field_index_[(c - n * (1 + P)) / n]) * n + (c - n * (1 + P)) % n].v[c - c0] = 1.0;
    }
    std::fill(dN.begin(), dN.end(), Jet(0.0));
    std::fill(dq.begin(), dq.end(), Jet(0.0));
    std::fill(out.begin(), out.end(), Jet(0.0));
    grown = Jet(0.0);
    rates_t(w, js, jr, false);  // folding is applied to D afterwards
    for (int c = c0; c < c1; ++c) {
      double* col = D.data() + size_t(c) * R;
      for (int i = 0; i < n; ++i) col[i] = dN[i].v[c - c0];
      for (int p = 0; p < P; ++p)
        for (int i = 0; i < n; ++i) col[size_t(n) * (1 + p) + i] = dq[size_t(p) * n + i].v[c - c0];
      for (int k = 0; k < no; ++k) col[size_t(n) * (1 + P) + k] = out[k].v[c - c0];
      col[size_t(n) * (1 + P) + no] = grown.v[c - c0];
    }
  }
}

}  // namespace granuflow::kernels
