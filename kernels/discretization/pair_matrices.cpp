// The run schemes' sums for size-only kernels (pair_runs.hpp): the pairs of the runs as lower-triangular
// matrix-vector products, or for a separable kernel as prefix sums; the diagonals as vector loops; and the tables
// behind them: the grid-only layout (built once per grid) and the matrices of the kernel's values (per parameter
// change).
#include <Eigen/Dense>
#include <cmath>

#include "discretization/cell_average.hpp"
#include "discretization/fixed_pivot.hpp"
#include "discretization/pair_runs.hpp"

namespace granuflow::kernels {

template <class S>
void aggregate_diagonals(const S& s, RunTables& t, const AggregationArgs<double>& a, const double* stored) {
  auto& sc = t.sd;
  const int n = a.n, P = a.P;
  const double* N = a.N;
  const double* pi = a.pi;
  double *dN = a.dN, *dq = a.dq;
  double* formed = stored ? nullptr : sc.mv.data() + 4 * n;
  const int nd = static_cast<int>(s.diagonals().size());
  const auto& x = a.grid->pivots();
  std::vector<double> carried(kFixedPivot<S> && P > 0 ? size_t(n) : 0);  // rt (pi_j + pi_k) along a diagonal
  for (int d = 0; d < nd; ++d) {
    const auto& diag = s.diagonals()[d];
    const int last = diag.last, sh = diag.shift;
    const double* rt = formed;
    if (stored) {
      rt = stored + size_t(d) * n;
    } else {
      const double* kd = t.Kd.data() + size_t(d) * n;
#pragma omp simd
      for (int k = d; k <= last; ++k) formed[k] = kd[k] * N[k - d] * N[k];
    }
    if constexpr (kFixedPivot<S>) {
      double* lo = dN + sh;
#pragma omp simd
      for (int k = d; k <= last; ++k) lo[k] += diag.w_lo * rt[k];
      double* hi = dN + sh + 1;
#pragma omp simd
      for (int k = d; k <= last; ++k) hi[k] += diag.w_hi * rt[k];
      // Entry k + sh + 1 receives pair k's upper share before pair k + 1's lower one: all upper shares, then all
      // lower ones, is that order per entry (the same sums to the bit) as two vector loops.
      for (int p = 0; p < P; ++p) {
        const double* pp = pi + size_t(p) * n;
        double* dqp = dq + size_t(p) * n;
#pragma omp simd
        for (int k = d; k <= last; ++k) carried[k] = rt[k] * (pp[k - d] + pp[k]);
        double* qhi = dqp + sh + 1;
#pragma omp simd
        for (int k = d; k <= last; ++k) qhi[k] += diag.f_hi * carried[k];
        double* qlo = dqp + sh;
#pragma omp simd
        for (int k = d; k <= last; ++k) qlo[k] += diag.f_lo * carried[k];
      }
    } else {
      double *B = sc.B.data() + sh, *V = sc.V.data() + sh;
#pragma omp simd
      for (int k = d; k <= last; ++k) B[k] += rt[k];
#pragma omp simd
      for (int k = d; k <= last; ++k) V[k] += (x[k - d] + x[k]) * rt[k];
      for (int p = 0; p < P; ++p) {
        const double* pp = pi + size_t(p) * n;
        double* Qp = sc.Q.data() + size_t(p) * (n + 1) + sh;
        for (int k = d; k <= last; ++k) Qp[k] += rt[k] * (pp[k - d] + pp[k]);
      }
    }
  }
  if (stored) return;
  for (const auto& [pr, jk] : t.rest(s.layout())) {
    const int j = jk.first, k = jk.second;
    if (N[j] != 0.0 && N[k] != 0.0) place_pair(s, sc, a, pr, j, k, a.Kh[pr] * N[j] * N[k]);
  }
}

// Aggregation of a size-only kernel (RunTables::matrices) without a loop over pairs: deaths N_k (K N)_k over all pairs
// (K symmetric, its lower triangle read); the pairs of the scheme's runs through A, Bm, F, G (fixed pivot) or C, Vc
// (cell average: the packets B, V, Q of cell k), lower-triangular matrix-vector products; then the diagonals and the
// rest.
template <class S>
void aggregate_by_matrices(const S& s, RunTables& t, const AggregationArgs<double>& a) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using Vec = Eigen::Map<Eigen::VectorXd>;
  auto& sc = t.sd;
  const int n = a.n, P = a.P;
  const double* N = a.N;
  double *dN = a.dN, *dq = a.dq;
  auto matrix = [n](const std::vector<double>& m) { return Eigen::Map<const RowMajor>(m.data(), n, n); };
  const Eigen::Map<const Eigen::VectorXd> Nv(N, n);
  sc.mv.resize(size_t(5) * n);
  Vec kN(sc.mv.data(), n), u(sc.mv.data() + n, n), v(sc.mv.data() + 2 * n, n), r(sc.mv.data() + 3 * n, n);
  if (t.folded) {  // fixed pivot without properties: births on k and deaths in one product, (A - K) N
    u.noalias() = matrix(t.Am) * Nv;
    v.noalias() = matrix(t.Bm).template triangularView<Eigen::Lower>() * Nv;
    for (int k = 0; k < n; ++k) dN[k] += N[k] * u[k];
    for (int k = 0; k + 1 < n; ++k) dN[k + 1] += N[k] * v[k];
  } else {
    kN.noalias() = matrix(t.Km) * Nv;  // the full symmetric K: a plain product beats the symmetric one
    for (int k = 0; k < n; ++k) dN[k] -= N[k] * kN[k];
  }
  const double* pi = a.pi;
  for (int p = 0; p < P; ++p)
    for (int k = 0; k < n; ++k) dq[size_t(p) * n + k] -= pi[size_t(p) * n + k] * N[k] * kN[k];
  // with u = M N and v = M r, r = N pi: what the run pairs of row k carry of property p
  auto carried = [&](int p, int k) { return N[k] * (v[k] + pi[size_t(p) * n + k] * u[k]); };
  auto lower = [&](const std::vector<double>& m, const auto& x, Vec& y) {
    y.noalias() = matrix(m).template triangularView<Eigen::Lower>() * x;
  };
  if constexpr (kFixedPivot<S>) {
    if (!t.folded) {
      lower(t.Am, Nv, u);
      lower(t.Bm, Nv, v);
      for (int k = 0; k < n; ++k) dN[k] += N[k] * u[k];
      for (int k = 0; k + 1 < n; ++k) dN[k + 1] += N[k] * v[k];
      for (int p = 0; p < P; ++p) {
        for (int k = 0; k < n; ++k) r[k] = N[k] * pi[size_t(p) * n + k];
        for (const auto* m : {&t.Fm, &t.Gm}) {
          lower(*m, Nv, u);
          lower(*m, r, v);
          const int shift = m == &t.Gm;
          for (int k = 0; k + shift < n; ++k) dq[size_t(p) * n + k + shift] += carried(p, k);
        }
      }
    }
  } else {
    lower(t.Cm, Nv, u);
    lower(t.Vc, Nv, v);
    for (int k = 0; k < n; ++k) sc.B[k] += N[k] * u[k], sc.V[k] += N[k] * v[k];
    for (int p = 0; p < P; ++p) {
      for (int k = 0; k < n; ++k) r[k] = N[k] * pi[size_t(p) * n + k];
      lower(t.Cm, Nv, u);
      lower(t.Cm, r, v);
      for (int k = 0; k < n; ++k) sc.Q[size_t(p) * (n + 1) + k] += carried(p, k);
    }
  }
  aggregate_diagonals(s, t, a);
}

// Aggregation of a separable size-only kernel without carried properties (RunTables::terms): with S_t(J) = sum_{j <=
// J} a_t(j) N_j and X_t(J) = sum_{j <= J} a_t(j) N_j x_j, the run pairs of row k give, per term, N_k b_t(k) times
//   fixed pivot (Kumar & Ramkrishna 1996, Eq. (9) with v = x_j + x_k in [x_k, x_{k+1})):
//     births on k: S_t - X_t / (x_{k+1} - x_k),   births on k + 1 (or above the grid): X_t / (x_{k+1} - x_k);
//   cell average (Kumar et al. 2006, Eq. (13)): packet number S_t and volume X_t + x_k S_t in cell k;
// and the deaths of class k are N_k sum_t b_t(k) S_t(n - 1). Then the diagonals and the rest as above.
template <class S>
void aggregate_separable(const S& s, RunTables& t, const AggregationArgs<double>& a) {
  auto& sc = t.sd;
  const RunLayout& L = s.layout();
  const int n = a.n;
  const double* N = a.N;
  double *dN = a.dN, *out = a.out;
  const auto& x = a.grid->pivots();
  sc.mv.resize(size_t(5) * n);
  double* sum0 = sc.mv.data();        // per row: sum_t b_t(k) S_t(J(k))
  double* sum1 = sum0 + n;            // sum_t b_t(k) X_t(J(k))
  double* death = sum0 + 2 * n;       // sum_t b_t(k) S_t(n - 1)
  double* cs = sc.mv.data() + 3 * n;  // S_t, then X_t below (2 n)
  for (int k = 0; k < n; ++k) sum0[k] = sum1[k] = death[k] = 0.0;
  for (int term = 0; term < t.terms; ++term) {
    const double* ta = t.ta.data() + size_t(term) * n;
    const double* tb = t.tb.data() + size_t(term) * n;
    double* Sp = cs;
    double* X = cs + n;
    double s0 = 0.0, s1 = 0.0;
    for (int j = 0; j < n; ++j) {
      const double aN = ta[j] * N[j];
      s0 += aN, s1 += aN * x[j];
      Sp[j] = s0, X[j] = s1;
    }
    for (int k = 0; k < n; ++k) {
      death[k] += tb[k] * s0;
      const int J = L.prefix_end[k];
      if (J >= 0) sum0[k] += tb[k] * Sp[J], sum1[k] += tb[k] * X[J];
    }
  }
  if constexpr (kFixedPivot<S>) {
    const double* gap = L.inv_gap.data();
    for (int k = 0; k < n; ++k) {
      const double up = N[k] * sum1[k] * gap[k];
      dN[k] += N[k] * (sum0[k] - death[k]) - up;
      if (k + 1 < n) {
        dN[k + 1] += up;
      } else {
        out[kOutNumberAbove] += up;
        out[kOutVolumeAbove] += up * a.grid->upper_virtual();
      }
    }
  } else {
    for (int k = 0; k < n; ++k) {
      dN[k] -= N[k] * death[k];
      sc.B[k] += N[k] * sum0[k];
      sc.V[k] += N[k] * (sum1[k] + x[k] * sum0[k]);
    }
  }
  aggregate_diagonals(s, t, a);
}

namespace {
template <class S>
bool on_diagonal(const S& s, int j, int k) {
  const int d = k - j;
  return d < static_cast<int>(s.diagonals().size()) && k <= s.diagonals()[d].last;
}

// RunLayout's prefixes: row k's prefix is the longest run of partners j = 0, 1, ... off the diagonals whose aggregates
// the scheme places like a run pair (fixed pivot: on k and k + 1, or on k and above the grid for the top class; cell
// average: in cell k); every other pair off the diagonals is in rest_separable. False (use the matrices) if a prefix
// pair's table weights differ from the affine form the prefix sums assume.
template <class S>
bool separable_layout(const S& s, const Grid& g, RunLayout& L) {
  const int n = g.size();
  L.prefix_end.assign(n, -1);
  L.inv_gap.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const double gap = g.pivot_ext(k + 1) - g.pivot(k);
    L.inv_gap[k] = 1.0 / gap;
    int J = -1;
    for (int j = 0; j < k && !on_diagonal(s, j, k); ++j) {
      const size_t pr = pair_index(j, k, n);
      if constexpr (kFixedPivot<S>) {
        const auto& t = s.target(pr);
        if (t.lo != k || t.hi != (k + 1 < n ? k + 1 : -1)) break;
        if (std::abs(t.w_hi - g.pivot(j) / gap) > 1e-12) return false;
      } else if (s.cell(pr) != k) {
        break;
      }
      J = j;
    }
    L.prefix_end[k] = J;
  }
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k)
      if (j > L.prefix_end[k] && !on_diagonal(s, j, k)) L.rest_separable.push_back({pair_index(j, k, n), {j, k}});
  return true;
}
}  // namespace

template <class S>
void build_run_layout(const S& s, const Grid& g, RunLayout& L) {
  const int n = g.size();
  L.rest_separable.clear(), L.rest_matrices.clear();
  L.separable = separable_layout(s, g, L);
  if (!L.separable) L.rest_separable.clear();
  size_t p0 = 0;
  L.rest_row.assign(size_t(n) + 1, 0);
  for (int j = 0; j < n; p0 += n - j, ++j) {
    const int a = s.run_first(j), b = s.run_last(j);
    for (int k = j; k < n; ++k)
      if (!(a <= k && k <= b) && !on_diagonal(s, j, k)) L.rest_matrices.push_back({p0 + (k - j), {j, k}});
    L.rest_row[j + 1] = L.rest_matrices.size();
  }
}

// The matrices of RunTables::matrices from the pair table Kh (see there), or the separable form's terms.
template <class S>
void refresh_run_tables(const S& s, RunTables& t, const AggregationTableInputs& in) {
  const int n = in.grid->size();
  const RunLayout& L = s.layout();
  const std::vector<double>& Kh = *in.Kh;
  t.matrices = in.kernel->n_features() == 0;
  t.terms = 0;
  if (!t.matrices) return;
  const size_t nd = s.diagonals().size();
  auto diagonal_pairs = [&] {
    t.Kd.assign(nd * n, 0.0);
    for (size_t d = 0; d < nd; ++d)
      for (int k = static_cast<int>(d); k < n; ++k) t.Kd[d * n + k] = Kh[pair_index(k - static_cast<int>(d), k, n)];
  };
  if (in.P == 0) {
    t.ta.assign(size_t(kMaxFactorTerms) * n, 0.0), t.tb.assign(size_t(kMaxFactorTerms) * n, 0.0);
    t.terms = in.kernel->factor_terms(*in.cs, in.p, t.ta.data(), t.tb.data());
    if (t.terms > 0 && L.separable) {
      diagonal_pairs();
      t.Km.clear(), t.Am.clear(), t.Bm.clear(), t.Fm.clear(), t.Gm.clear(), t.Cm.clear(), t.Vc.clear();
      t.folded = false;
      return;
    }
    t.terms = 0;
  }
  constexpr bool fp = kFixedPivot<S>, ca = !fp;
  const size_t nn = size_t(n) * n;
  t.Km.assign(in.K->begin(), in.K->end());  // K is symmetric: row-major = column-major
  auto zero = [nn](std::vector<double>& m, bool used) { used ? m.assign(nn, 0.0) : m.clear(); };
  zero(t.Am, fp), zero(t.Bm, fp), zero(t.Fm, fp && in.P > 0), zero(t.Gm, fp && in.P > 0);
  zero(t.Cm, ca), zero(t.Vc, ca);
  size_t p0 = 0;
  for (int j = 0; j < n; p0 += n - j, ++j)
    for (int k = s.run_first(j); k <= s.run_last(j); ++k) {
      const size_t pr = p0 + (k - j), at = size_t(k) * n + j;
      const double kh = Kh[pr];
      if constexpr (fp) {
        const auto& tg = s.target(pr);
        t.Am[at] = tg.w_lo * kh, t.Bm[at] = tg.w_hi * kh;
        if (!t.Fm.empty()) t.Fm[at] = tg.f_lo * kh, t.Gm[at] = tg.f_hi * kh;
      } else {
        t.Cm[at] = kh, t.Vc[at] = s.volume(pr) * kh;
      }
    }
  t.folded = fp && in.P == 0;
  if (t.folded) {
    for (size_t i = 0; i < nn; ++i) t.Am[i] -= t.Km[i];
    t.Km.clear();
  }
  diagonal_pairs();
}

template <class S>
std::string run_evaluation(const RunTables& t) {
  return t.terms > 0 ? "separable" : t.matrices ? "matrices" : "pairs";
}

#define GRANUFLOW_RUN_SCHEME(S)                                                                              \
  template void aggregate_diagonals<S>(const S&, RunTables&, const AggregationArgs<double>&, const double*); \
  template void aggregate_by_matrices<S>(const S&, RunTables&, const AggregationArgs<double>&);              \
  template void aggregate_separable<S>(const S&, RunTables&, const AggregationArgs<double>&);                \
  template void build_run_layout<S>(const S&, const Grid&, RunLayout&);                                      \
  template void refresh_run_tables<S>(const S&, RunTables&, const AggregationTableInputs&);                  \
  template std::string run_evaluation<S>(const RunTables&);
GRANUFLOW_RUN_SCHEME(FixedPivotAggregation)
GRANUFLOW_RUN_SCHEME(CellAverageAggregation)
#undef GRANUFLOW_RUN_SCHEME

}  // namespace granuflow::kernels
