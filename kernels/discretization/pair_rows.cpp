// The row loop over the pair triangle of the run schemes (pair_runs.hpp): row j (partners k >= j, contiguous in the
// pair tables) forms the event rates in one vectorizable pass, the deaths, then the births. Most partners place their
// aggregate on k and k + 1 (fixed pivot) or keep it in cell k (cell average); those runs are plain array arithmetic
// (about 0.2 ns per pair instead of 1-2 ns through the table), the rest goes through place_pair(). Then the cell
// average's packets are split (Kumar et al. 2006, Eq. (15)).
#include <algorithm>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "discretization/cell_average.hpp"
#include "discretization/fixed_pivot.hpp"
#include "discretization/pair_runs.hpp"

namespace granuflow::kernels {

namespace {

// Event rates of row j of the pair triangle, rt[k] = h K_jk E_jk N_j N_k for k >= j (paper 001, Eqs. (21), (24)),
// and their sum (the deaths of class j). The double version is vectorized, its sum included.
double row_rates(const double* kh, const double* e, double Nj, const double* N, int j, int n, double* rt) {
  double death = 0.0;
  if (e) {
#pragma omp simd reduction(+ : death)
    for (int k = j; k < n; ++k) {
      rt[k] = kh[k] * e[k] * Nj * N[k];
      death += rt[k];
    }
  } else {
#pragma omp simd reduction(+ : death)
    for (int k = j; k < n; ++k) {
      rt[k] = kh[k] * Nj * N[k];
      death += rt[k];
    }
  }
  return death;
}
Jet row_rates(const Jet* kh, const Jet* e, const Jet& Nj, const Jet* N, int j, int n, Jet* rt) {
  Jet death(0.0);
  for (int k = j; k < n; ++k) {
    rt[k] = (e ? kh[k] * e[k] : kh[k]) * Nj * N[k];
    death += rt[k];
  }
  return death;
}

// Row j of the pair triangle for fixed pivot in doubles: the event rates rt[k] = h K_jk (E_jk) N_j N_k, the deaths
// of both partners, and the births of the run [run_first, run_last] on k and k + 1 (those on k + 1 into `up`, rows
// 1 + p for property p, n + 1 wide), in one loop over all partners: off the run the scheme's weights are 0 and the
// caller places those births. With one carried property (OneProperty: the fluid bed's water) it moves in the same
// pass as the numbers; more properties follow in a pass each. Returns the deaths of class j.
template <bool HasE, bool OneProperty>
double fixed_pivot_partners(const FixedPivotAggregation& fp, size_t p0, int j, int n, const double* kh, const double* e,
                            const double* N, const double* q, double* rt, double* dN, double* dq0, double* up,
                            double* up0) {
  const double Nj = N[j];
  const double qj = OneProperty ? q[j] : 0.0;
  const double *wl = fp.w_lo() + (p0 - j), *wh = fp.w_hi() + (p0 - j);
  const double *fl = fp.f_lo() + (p0 - j), *fh = fp.f_hi() + (p0 - j);
#if defined(__AVX512F__)
  // A row is n - j partners long, 20 on average at 40 classes: a vector loop's scalar remainder (up to 7 partners)
  // cost as much as its vector part. Here the last 8-wide step is masked instead; each partner's arithmetic is the
  // scalar code's, operation for operation (no fused multiply-adds), only the deaths are summed lane by lane.
  const __m512d vNj = _mm512_set1_pd(Nj), vqj = _mm512_set1_pd(qj);
  __m512d death = _mm512_setzero_pd();
  for (int k = j; k < n; k += 8) {
    const __mmask8 m = n - k >= 8 ? __mmask8(0xff) : __mmask8((1u << (n - k)) - 1u);
    __m512d r = _mm512_maskz_loadu_pd(m, kh + k);
    if constexpr (HasE) r = _mm512_mul_pd(r, _mm512_maskz_loadu_pd(m, e + k));
    r = _mm512_mul_pd(_mm512_mul_pd(r, vNj), _mm512_maskz_loadu_pd(m, N + k));
    _mm512_mask_storeu_pd(rt + k, m, r);
    death = _mm512_add_pd(death, r);
    const __m512d born_lo = _mm512_sub_pd(_mm512_mul_pd(_mm512_maskz_loadu_pd(m, wl + k), r), r);
    _mm512_mask_storeu_pd(dN + k, m, _mm512_add_pd(_mm512_maskz_loadu_pd(m, dN + k), born_lo));
    const __m512d born_hi = _mm512_mul_pd(_mm512_maskz_loadu_pd(m, wh + k), r);
    _mm512_mask_storeu_pd(up + k + 1, m, _mm512_add_pd(_mm512_maskz_loadu_pd(m, up + k + 1), born_hi));
    if constexpr (OneProperty) {
      const __m512d qk = _mm512_maskz_loadu_pd(m, q + k);
      const __m512d carried = _mm512_mul_pd(r, _mm512_add_pd(vqj, qk));
      const __m512d moved =
          _mm512_sub_pd(_mm512_mul_pd(_mm512_maskz_loadu_pd(m, fl + k), carried), _mm512_mul_pd(r, qk));
      _mm512_mask_storeu_pd(dq0 + k, m, _mm512_add_pd(_mm512_maskz_loadu_pd(m, dq0 + k), moved));
      const __m512d moved_hi = _mm512_mul_pd(_mm512_maskz_loadu_pd(m, fh + k), carried);
      _mm512_mask_storeu_pd(up0 + k + 1, m, _mm512_add_pd(_mm512_maskz_loadu_pd(m, up0 + k + 1), moved_hi));
    }
  }
  alignas(64) double d[8];  // the lanes summed as a tree (GCC 12's _mm512_reduce_add_pd warns on its own header)
  _mm512_store_pd(d, death);
  return ((d[0] + d[4]) + (d[2] + d[6])) + ((d[1] + d[5]) + (d[3] + d[7]));
#else
  auto rate = [kh, e, Nj, N](int k) {  // by value: loads through captured references would not vectorize
    if constexpr (HasE) {
      return kh[k] * e[k] * Nj * N[k];
    } else {
      (void)e;  // captured for the other instantiation
      return kh[k] * Nj * N[k];
    }
  };
  double death = 0.0;
#pragma omp simd reduction(+ : death)
  for (int k = j; k < n; ++k) {
    const double r = rate(k);
    rt[k] = r;
    death += r;
    dN[k] += wl[k] * r - r;
    up[k + 1] += wh[k] * r;
    if constexpr (OneProperty) {
      const double carried = r * (qj + q[k]);
      dq0[k] += fl[k] * carried - r * q[k];
      up0[k + 1] += fh[k] * carried;
    }
  }
  return death;
#endif
}

template <bool HasE, bool OneProperty>
void fixed_pivot_row(const FixedPivotAggregation& fp, size_t p0, int j, int n, int P, const double* kh, const double* e,
                     const double* N, const double* pi, double* rt, double* dN, double* dq, double* up) {
  const double death =
      fixed_pivot_partners<HasE, OneProperty>(fp, p0, j, n, kh, e, N, pi, rt, dN, dq, up, up + (n + 1));
  dN[j] -= death;
  if constexpr (OneProperty) {
    dq[j] -= death * pi[j];
    return;
  }
  const double *fl = fp.f_lo() + (p0 - j), *fh = fp.f_hi() + (p0 - j);
  for (int p = 0; p < P; ++p) {
    const double* pp = pi + size_t(p) * n;
    double* dqp = dq + size_t(p) * n;
    double* upq = up + size_t(1 + p) * (n + 1);
    const double pj = pp[j];
#pragma omp simd
    for (int k = j; k < n; ++k) {
      const double carried = rt[k] * (pj + pp[k]);
      dqp[k] += fl[k] * carried - rt[k] * pp[k];
      upq[k + 1] += fh[k] * carried;
    }
    dqp[j] -= death * pj;
  }
}

// Row j without the fused form: event rates and the deaths of both partners, with their properties.
template <class T>
void row_deaths(const AggregationArgs<T>& a, const T* kh, const T* e, int j, T* rt) {
  const int n = a.n;
  T* dN = a.dN;
  const T death = row_rates(kh, e, a.N[j], a.N, j, n, rt);
#pragma omp simd
  for (int k = j; k < n; ++k) dN[k] -= rt[k];
  dN[j] -= death;
  for (int p = 0; p < a.P; ++p) {
    const T* pp = a.pi + size_t(p) * n;
    T* dqp = a.dq + size_t(p) * n;
#pragma omp simd
    for (int k = j; k < n; ++k) dqp[k] -= rt[k] * pp[k];
    dqp[j] -= death * pp[j];
  }
}

// The births of the run [first, last] of row j (pair p0 = (j, j)) without the fused form.
template <class S, class T>
void run_births(const S& s, RunTables::Scratch<T>& sc, const AggregationArgs<T>& a, size_t p0, int j, int first,
                int last, const T* rt) {
  const int n = a.n;
  const T* pi = a.pi;
  if constexpr (kFixedPivot<S>) {
    T* dN = a.dN;
    const double *wl = s.w_lo() + (p0 - j), *wh = s.w_hi() + (p0 - j);
    T* up = sc.up.data();
#pragma omp simd
    for (int k = first; k <= last; ++k) {
      dN[k] += wl[k] * rt[k];
      up[k + 1] += wh[k] * rt[k];
    }
    const double *fl = s.f_lo() + (p0 - j), *fh = s.f_hi() + (p0 - j);
    for (int p = 0; p < a.P; ++p) {
      const T* pp = pi + size_t(p) * n;
      T* dqp = a.dq + size_t(p) * n;
      T* upq = up + size_t(1 + p) * (n + 1);
      const T pj = pp[j];
#pragma omp simd
      for (int k = first; k <= last; ++k) {
        const T carried = rt[k] * (pj + pp[k]);
        dqp[k] += fl[k] * carried;
        upq[k + 1] += fh[k] * carried;
      }
    }
  } else {
    const double* vol = s.volumes() + (p0 - j);
    T *B = sc.B.data(), *V = sc.V.data();
#pragma omp simd
    for (int k = first; k <= last; ++k) {
      B[k] += rt[k];
      V[k] += vol[k] * rt[k];
    }
    for (int p = 0; p < a.P; ++p) {
      const T* pp = pi + size_t(p) * n;
      T* Qp = sc.Q.data() + size_t(p) * (n + 1);
      const T pj = pp[j];
#pragma omp simd
      for (int k = first; k <= last; ++k) Qp[k] += rt[k] * (pj + pp[k]);
    }
  }
}

// Each packet of the cell average split on the side of its mean volume (Kumar et al. 2006, Eq. (15)); properties
// follow the volume. A packet touches at most classes a and a + 1 and the outside rows: only those entries of
// `split` are read and then cleared, so the loop costs O(n), not O(n^2).
template <class T>
void split_packets(const CellAverageAggregation& ca, RunTables::Scratch<T>& sc, const AggregationArgs<T>& ar) {
  const int n = ar.n, P = ar.P;
  const Grid& g = *ar.grid;
  const auto& x = g.pivots();
  T *dN = ar.dN, *dq = ar.dq, *out = ar.out;
  sc.split.assign(n + kOutsideRows, T(0.0));
  T* split = sc.split.data();
  for (int c = 0; c < n; ++c) {
    if (is_empty(sc.B[c])) continue;
    const int a = ca.side(g, c, sc.B[c], sc.V[c]);
    const int lo = std::max(a, 0), hi = std::min(a + 1, n - 1);
    split_between(g, a, sc.B[c], sc.V[c], split);
    for (int i = lo; i <= hi; ++i) dN[i] += split[i];
    out[kOutNumberAbove] += split[n + kNumberAbove];
    out[kOutVolumeAbove] += split[n + kVolumeAbove];
    out[kOutVolumeBelow] += split[n + kVolumeBelow];
    for (int p = 0; p < P && value_of(sc.V[c]) != 0.0; ++p) {
      const T per_volume = sc.Q[size_t(p) * (n + 1) + c] / sc.V[c];
      for (int i = lo; i <= hi; ++i) dq[size_t(p) * n + i] += per_volume * x[i] * split[i];
      out[out_property_above(p)] += per_volume * split[n + kVolumeAbove];
      out[out_property_below(p)] += per_volume * split[n + kVolumeBelow];
    }
    for (int i = lo; i <= hi; ++i) split[i] = T(0.0);
    for (int i = n; i < n + kOutsideRows; ++i) split[i] = T(0.0);
  }
  out[kOutNumberAbove] += sc.B[n];  // aggregates beyond the top edge leave whole
  out[kOutVolumeAbove] += sc.V[n];
  for (int p = 0; p < P; ++p) out[out_property_above(p)] += sc.Q[size_t(p) * (n + 1) + n];
}

}  // namespace

// With doubles, the pairs along the scheme's diagonals (near-equal partners) are stored by diagonal and summed after
// the rows as vector loops (aggregate_diagonals), not placed one by one; fixed pivot rows in doubles are fused
// (fixed_pivot_row).
template <class S, class T>
void aggregate_rows(const S& s, RunTables& t, const AggregationArgs<T>& a) {
  const int n = a.n, P = a.P;
  const T* N = a.N;
  const T* E = a.E;
  auto& sc = t.scratch<T>();
  T* rt = sc.rate.data();
  int nd = 0;
  if constexpr (std::is_same_v<T, double>) {
    nd = static_cast<int>(s.diagonals().size());
    if (nd > 0) sc.diag.assign(size_t(nd) * n, 0.0);
  }
  auto on_diagonal = [&](int d, int k) { return d < nd && k <= s.diagonals()[d].last; };
  size_t p0 = 0;  // pair (j, j)
  for (int j = 0; j < n; p0 += n - j, ++j) {
    if (is_empty(N[j])) continue;
    const T* kh = a.Kh + (p0 - j);  // kh[k]: pair (j, k)
    const int first = s.run_first(j), last = s.run_last(j);
    bool fused = false;
    if constexpr (std::is_same_v<T, double> && kFixedPivot<S>) {
      const double* e = E ? E + (p0 - j) : nullptr;
      auto row = e ? (P == 1 ? fixed_pivot_row<true, true> : fixed_pivot_row<true, false>)
                   : (P == 1 ? fixed_pivot_row<false, true> : fixed_pivot_row<false, false>);
      row(s, p0, j, n, P, kh, e, N, a.pi, rt, a.dN, a.dq, sc.up.data());
      fused = true;
    }
    if (!fused) row_deaths(a, kh, E ? E + (p0 - j) : nullptr, j, rt);
    if constexpr (std::is_same_v<T, double>) {
      // The same pairs as the loop below, from the grid's tables: a test per partner there cost as much as the
      // fused row itself at 80 classes.
      const auto& diags = s.diagonals();
      for (int d = 0; d < nd && j + d < n; ++d) {
        const int k = j + d;
        if (k <= diags[d].last && !(first <= k && k <= last)) sc.diag[size_t(d) * n + k] = rt[k];
      }
      const RunLayout& L = s.layout();
      for (size_t q = L.rest_row[j]; q < L.rest_row[j + 1]; ++q) {
        const int k = L.rest_matrices[q].second.second;
        if (!is_empty(N[k])) place_pair(s, sc, a, L.rest_matrices[q].first, j, k, rt[k]);
      }
      if (first > last || fused) continue;
      run_births(s, sc, a, p0, j, first, last, rt);
      continue;
    }
    for (int k = j; k < n; ++k) {
      if (k == first) k = last + 1;  // the run, below
      if (k >= n) break;
      if (on_diagonal(k - j, k)) {
        sc.diag[size_t(k - j) * n + k] = rt[k];
        continue;
      }
      if (!is_empty(N[k])) place_pair(s, sc, a, p0 + (k - j), j, k, rt[k]);
    }
    if (first > last || fused) continue;
    run_births(s, sc, a, p0, j, first, last, rt);
  }
  if constexpr (std::is_same_v<T, double>)
    if (nd > 0) aggregate_diagonals(s, t, a, sc.diag.data());
  if constexpr (kFixedPivot<S>) {
    for (int i = 0; i < n; ++i) a.dN[i] += sc.up[i];
    for (int p = 0; p < P; ++p)
      for (int i = 0; i < n; ++i) a.dq[size_t(p) * n + i] += sc.up[size_t(1 + p) * (n + 1) + i];
  }
}

template <class S, class T>
void run_rates(const S& s, RunTables& t, const AggregationArgs<T>& a) {
  const int n = a.n, P = a.P;
  auto& sc = t.scratch<T>();
  if constexpr (kFixedPivot<S>) {
    sc.up.assign(size_t(1 + P) * (n + 1), T(0.0));  // births the runs place on k + 1, added after the loop
  } else {
    sc.B.assign(n + 1, T(0.0));
    sc.V.assign(n + 1, T(0.0));
    sc.Q.assign(size_t(P) * (n + 1), T(0.0));
  }
  sc.rate.resize(n);
  bool by_matrices = false;
  if constexpr (std::is_same_v<T, double>) by_matrices = t.matrices && !a.E;
  if constexpr (std::is_same_v<T, double>) {
    if (by_matrices && t.terms > 0)
      aggregate_separable(s, t, a);
    else if (by_matrices)
      aggregate_by_matrices(s, t, a);
  }
  if (!by_matrices) aggregate_rows(s, t, a);
  if constexpr (!kFixedPivot<S>) split_packets(s, sc, a);
}

#define GRANUFLOW_RUN_SCHEME(S, T)                                                     \
  template void aggregate_rows<S, T>(const S&, RunTables&, const AggregationArgs<T>&); \
  template void run_rates<S, T>(const S&, RunTables&, const AggregationArgs<T>&);
GRANUFLOW_RUN_SCHEME(FixedPivotAggregation, double)
GRANUFLOW_RUN_SCHEME(FixedPivotAggregation, Jet)
GRANUFLOW_RUN_SCHEME(CellAverageAggregation, double)
GRANUFLOW_RUN_SCHEME(CellAverageAggregation, Jet)
#undef GRANUFLOW_RUN_SCHEME

}  // namespace granuflow::kernels
