#include "population/population.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>
#if defined(__AVX512F__)
#include <immintrin.h>
#elif defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include "discretization/cell_average.hpp"
#include "discretization/fixed_pivot.hpp"
#include "discretization/redistribution.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "registry.hpp"

namespace granuflow::kernels {

namespace {
constexpr const char* kNone = "none";

// The far tails of a size distribution (classes thousands of times the start volume) hold numbers like 1e-310, and
// products of them are subnormal: arithmetic on subnormals costs a hundred cycles, which doubled the cost of an
// aggregation right-hand side. While the engine evaluates, they count as zero (flush-to-zero, denormals-are-zero):
// a change below 2.2e-308 in any number, restored on leaving.
class FlushDenormals {
 public:
#if defined(__SSE__) || defined(__x86_64__)
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040); }
  ~FlushDenormals() { _mm_setcsr(saved_); }

 private:
  unsigned saved_;
#endif
};

std::vector<std::string> with_none(std::vector<std::string> names) {
  names.insert(names.begin(), kNone);
  return names;
}

bool has_derivative(const double*, int, int) { return false; }
bool has_derivative(const Jet* p, int first, int count) {
  for (int k = first; k < first + count; ++k)
    if (!p[k].v.isZero()) return true;
  return false;
}

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
    if constexpr (HasE)
      return kh[k] * e[k] * Nj * N[k];
    else
      return kh[k] * Nj * N[k];
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

// sum_{k = first}^{n - 1} b_k x_k: a row of the breakage tables against the classes.
inline Jet upper_dot(const Jet* b, const Jet* x, int first, int n) {
  Jet acc(0.0);
  for (int k = first; k < n; ++k) acc += b[k] * x[k];
  return acc;
}

// acc = B x for a breakage table B (rows x n, row-major): class rows r < n hold parents k >= r only (fragments land at
// or below the parent's pivot), the outside rows every parent. In doubles one matrix-vector product over whole rows
// (Eigen's vector kernel; the zeros left of the diagonal cost less than a horizontal sum at the end of every row).
inline void table_times(const double* B, int rows, int n, const double* x, double* acc) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Map<Eigen::VectorXd>(acc, rows).noalias() =
      Eigen::Map<const RowMajor>(B, rows, n) * Eigen::Map<const Eigen::VectorXd>(x, n);
}
inline void table_times(const Jet* B, int rows, int n, const Jet* x, Jet* acc) {
  for (int row = 0; row < rows; ++row) acc[row] = upper_dot(B + size_t(row) * n, x, row < n ? row : 0, n);
}

Jet row_rates(const Jet* kh, const Jet* e, const Jet& Nj, const Jet* N, int j, int n, Jet* rt) {
  Jet death(0.0);
  for (int k = j; k < n; ++k) {
    rt[k] = (e ? kh[k] * e[k] : kh[k]) * Nj * N[k];
    death += rt[k];
  }
  return death;
}

void to_jets(const std::vector<double>& v, std::vector<Jet>& out) {
  out.resize(v.size());
  for (size_t k = 0; k < v.size(); ++k) out[k] = Jet(v[k]);
}
}  // namespace

// h K per pair, row-major upper triangle.
template <class T>
void pack_pairs(const std::vector<T>& K, int n, std::vector<T>& Kh) {
  Kh.resize(pair_count(n));
  size_t q = 0;
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k, ++q) Kh[q] = (j == k ? 0.5 : 1.0) * K[size_t(j) * n + k];
}

// BN = A diag(S), BQ = (x_r / x_k) BN over the class rows and the volume-below row (divided by x_k).
template <class T>
void breakage_tables(const Grid& g, const T* A, const T* S, std::vector<T>& BN, std::vector<T>& BQ) {
  const int n = g.size();
  BN.resize(size_t(n + kOutsideRows) * n);
  BQ.resize(size_t(n + 1) * n);
  for (int r = 0; r < n + kOutsideRows; ++r)
    for (int k = 0; k < n; ++k) BN[size_t(r) * n + k] = A[size_t(r) * n + k] * S[k];
  for (int r = 0; r < n; ++r)
    for (int k = 0; k < n; ++k) BQ[size_t(r) * n + k] = BN[size_t(r) * n + k] * (g.pivot(r) / g.pivot(k));
  for (int k = 0; k < n; ++k) BQ[size_t(n) * n + k] = BN[size_t(n + kVolumeBelow) * n + k] / g.pivot(k);
}

const char* field_name(Field f) {
  static const char* names[kFields] = {"moisture", "spot_moisture", "temperature", "liquid_fraction",
                                       "wetted_fraction"};
  return names[static_cast<int>(f)];
}

// Everything one run of a population computes: the tables that depend on parameters only (refreshed when a
// parameter value changes), and the work arrays of the rates and the Jacobian.
struct Population::Work {
  std::vector<double> snapshot;  // kernel parameter values of the tables
  bool fresh = false;            // the tables were computed for `snapshot`
  std::vector<double> K, S, A;   // beta factors (n x n), selection rates (n), breakage matrix ((n + 3) x n)
  std::vector<Jet> A_jet;
  bool jets = false;  // the *_jet copies match the tables (made when a Jet evaluation first needs them)
  // Per pair j <= k (row-major upper triangle) h K_jk, h = 1/2 for like pairs: the event rate is Kh E N_j N_k.
  std::vector<double> Kh;
  std::vector<Jet> Kh_jet;
  // Size-only kernels (no per-pair efficiency): the pair sums as matrix products over row-major n x n matrices,
  // rows = the class whose rate is formed. Km: the full symmetric K (deaths: N_k (K N)_k). For the pairs of the
  // scheme's runs (the larger partner k keeps, or moves to k + 1, the aggregate): fixed pivot A (w_lo h K, births on
  // k), Bm (w_hi h K, births on k + 1), F, G (the same with the volume fractions, for carried properties); cell
  // average C (h K, events into cell k) and Vc ((x_j + x_k) h K, their volume). Empty when not used.
  bool matrices = false;
  bool folded = false;  // fixed pivot, no properties: Am holds A - K (births on k less all deaths), Km unused
  std::vector<double> Km, Am, Bm, Fm, Gm, Cm, Vc;
  std::vector<double> Kd;  // h K of the pairs (k - d, k) at [d n + k], for the scheme's diagonals
  std::vector<std::pair<size_t, std::pair<int, int>>> rest;  // pairs on neither a run nor a diagonal: (pair, (j, k))
  // Separable size factor (AggregationKernel::factor_terms) and no carried properties: K_jk = sum_t a_t(j) b_t(k).
  // Row k's run partners are then a prefix j <= J(k) (aggregates placed on k and k + 1 with w_hi = x_j / (x_{k+1} -
  // x_k), affine in x_j, or kept in cell k), so their births and all deaths are prefix sums: O(n) per term. No
  // matrices are built; Kd and rest cover the other pairs as above.
  int terms = 0;
  std::vector<double> ta, tb, cum;  // a and b (terms x n), prefix sums (2 per term, n each)
  std::vector<int> prefix_end;      // J(k); -1: no prefix
  std::vector<double> inv_gap;      // fixed pivot: 1 / (x_{k+1} - x_k), x_n the virtual pivot above the grid
  // Breakage with the selection rates folded in: BN = A diag(S) ((n + 3) x n) moves numbers, BQ = (x_r / x_k) BN
  // ((n + 1) x n: class rows, then the volume below) moves a property with its parent's share of volume.
  std::vector<double> BN, BQ;
  std::vector<Jet> BN_jet, BQ_jet;
  template <class T>
  struct Scratch {
    std::vector<T> K, Kh, S, A, BN, BQ, phi, E, pi, B, V, Q, shape, amount, F, rows, dq, rate, up, mv, split, diag, brk;
    std::vector<int> donor;
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  // Jacobian work
  std::vector<double> D, G, dB, dV, dQ, dF, jinv, map_factors, map_scales;
  std::vector<int> map_rows, map_cols;
  std::vector<Jet> jp, jN, jq, jf, jphi;
  std::vector<double> eff, eff_da, eff_db;  // analytic Jacobian: E and dE/dphi of every pair
};

// The near-equal partners of the scheme's diagonals (one shift and one set of weights per diagonal on a geometric
// grid) as vector loops over k. The event rates of diagonal d are `stored` + d n when given (a kernel with per-pair
// efficiencies, whose row loop formed them), else h K N_{k-d} N_k from Work::Kd; then, without `stored`, the few
// pairs left (the top of the grid, irregular grids) one by one.
template <class Scratch, class Place>
void aggregate_diagonals(const Population::Work& w, Scratch& sc, const double* N, int n, int P,
                         const FixedPivotAggregation* fp, const CellAverageAggregation* ca, const Grid& g, double* dN,
                         double* dq, Place&& place, const double* stored = nullptr) {
  const double* pi = sc.pi.data();
  double* formed = stored ? nullptr : sc.mv.data() + 4 * n;
  const int nd = fp ? static_cast<int>(fp->diagonals().size()) : static_cast<int>(ca->diagonals().size());
  const auto& x = g.pivots();
  for (int d = 0; d < nd; ++d) {
    const int last = fp ? fp->diagonals()[d].last : ca->diagonals()[d].last;
    const int s = fp ? fp->diagonals()[d].shift : ca->diagonals()[d].shift;
    const double* rt = formed;
    if (stored) {
      rt = stored + size_t(d) * n;
    } else {
      const double* kd = w.Kd.data() + size_t(d) * n;
#pragma omp simd
      for (int k = d; k <= last; ++k) formed[k] = kd[k] * N[k - d] * N[k];
    }
    if (fp) {
      const auto& t = fp->diagonals()[d];
      double* lo = dN + s;
#pragma omp simd
      for (int k = d; k <= last; ++k) lo[k] += t.w_lo * rt[k];
      double* hi = dN + s + 1;
#pragma omp simd
      for (int k = d; k <= last; ++k) hi[k] += t.w_hi * rt[k];
      for (int p = 0; p < P; ++p) {
        const double* pp = pi + size_t(p) * n;
        double* dqp = dq + size_t(p) * n;
        for (int k = d; k <= last; ++k) {
          const double c = rt[k] * (pp[k - d] + pp[k]);
          dqp[k + s] += t.f_lo * c, dqp[k + s + 1] += t.f_hi * c;
        }
      }
    } else {
      double *B = sc.B.data() + s, *V = sc.V.data() + s;
#pragma omp simd
      for (int k = d; k <= last; ++k) B[k] += rt[k];
#pragma omp simd
      for (int k = d; k <= last; ++k) V[k] += (x[k - d] + x[k]) * rt[k];
      for (int p = 0; p < P; ++p) {
        const double* pp = pi + size_t(p) * n;
        double* Qp = sc.Q.data() + size_t(p) * (n + 1) + s;
        for (int k = d; k <= last; ++k) Qp[k] += rt[k] * (pp[k - d] + pp[k]);
      }
    }
  }
  if (stored) return;
  for (const auto& [pr, jk] : w.rest) {
    const int j = jk.first, k = jk.second;
    if (N[j] != 0.0 && N[k] != 0.0) place(pr, j, k, w.Kh[pr] * N[j] * N[k]);
  }
}

// Aggregation of a size-only kernel (Work::matrices) without a loop over pairs: deaths N_k (K N)_k over all pairs
// (K symmetric, its lower triangle read); the pairs of the scheme's runs through A, Bm, F, G (fixed pivot) or C, Vc
// (cell average: the packets B, V, Q of cell k), lower-triangular matrix-vector products; the near-equal partners
// along the scheme's diagonals (one shift and one set of weights per diagonal on a geometric grid) as vector loops
// over k; and the few pairs left (the top of the grid, irregular grids) one by one through `place`.
template <class Scratch, class Place>
void aggregate_by_matrices(const Population::Work& w, Scratch& sc, const double* N, int n, int P,
                           const FixedPivotAggregation* fp, const CellAverageAggregation* ca, const Grid& g, double* dN,
                           double* dq, Place&& place) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using Vec = Eigen::Map<Eigen::VectorXd>;
  auto matrix = [n](const std::vector<double>& m) { return Eigen::Map<const RowMajor>(m.data(), n, n); };
  const Eigen::Map<const Eigen::VectorXd> Nv(N, n);
  sc.mv.resize(size_t(5) * n);
  Vec kN(sc.mv.data(), n), u(sc.mv.data() + n, n), v(sc.mv.data() + 2 * n, n), r(sc.mv.data() + 3 * n, n);
  if (w.folded) {  // fixed pivot without properties: births on k and deaths in one product, (A - K) N
    u.noalias() = matrix(w.Am) * Nv;
    v.noalias() = matrix(w.Bm).template triangularView<Eigen::Lower>() * Nv;
    for (int k = 0; k < n; ++k) dN[k] += N[k] * u[k];
    for (int k = 0; k + 1 < n; ++k) dN[k + 1] += N[k] * v[k];
  } else {
    kN.noalias() = matrix(w.Km) * Nv;  // the full symmetric K: a plain product beats the symmetric one
    for (int k = 0; k < n; ++k) dN[k] -= N[k] * kN[k];
  }
  const double* pi = sc.pi.data();
  for (int p = 0; p < P; ++p)
    for (int k = 0; k < n; ++k) dq[size_t(p) * n + k] -= pi[size_t(p) * n + k] * N[k] * kN[k];
  // with u = M N and v = M r, r = N pi: what the run pairs of row k carry of property p
  auto carried = [&](int p, int k) { return N[k] * (v[k] + pi[size_t(p) * n + k] * u[k]); };
  auto lower = [&](const std::vector<double>& m, const auto& x, Vec& y) {
    y.noalias() = matrix(m).template triangularView<Eigen::Lower>() * x;
  };
  if (fp && !w.folded) {
    lower(w.Am, Nv, u);
    lower(w.Bm, Nv, v);
    for (int k = 0; k < n; ++k) dN[k] += N[k] * u[k];
    for (int k = 0; k + 1 < n; ++k) dN[k + 1] += N[k] * v[k];
    for (int p = 0; p < P; ++p) {
      for (int k = 0; k < n; ++k) r[k] = N[k] * pi[size_t(p) * n + k];
      for (const auto* m : {&w.Fm, &w.Gm}) {
        lower(*m, Nv, u);
        lower(*m, r, v);
        const int shift = m == &w.Gm;
        for (int k = 0; k + shift < n; ++k) dq[size_t(p) * n + k + shift] += carried(p, k);
      }
    }
  } else if (!fp) {
    lower(w.Cm, Nv, u);
    lower(w.Vc, Nv, v);
    for (int k = 0; k < n; ++k) sc.B[k] += N[k] * u[k], sc.V[k] += N[k] * v[k];
    for (int p = 0; p < P; ++p) {
      for (int k = 0; k < n; ++k) r[k] = N[k] * pi[size_t(p) * n + k];
      lower(w.Cm, Nv, u);
      lower(w.Cm, r, v);
      for (int k = 0; k < n; ++k) sc.Q[size_t(p) * (n + 1) + k] += carried(p, k);
    }
  }
  aggregate_diagonals(w, sc, N, n, P, fp, ca, g, dN, dq, place);
}

// Aggregation of a separable size-only kernel without carried properties (Work::terms): with S_t(J) = sum_{j <= J}
// a_t(j) N_j and X_t(J) = sum_{j <= J} a_t(j) N_j x_j, the run pairs of row k give, per term, N_k b_t(k) times
//   fixed pivot (Kumar & Ramkrishna 1996, Eq. (9) with v = x_j + x_k in [x_k, x_{k+1})):
//     births on k: S_t - X_t / (x_{k+1} - x_k),   births on k + 1 (or above the grid): X_t / (x_{k+1} - x_k);
//   cell average (Kumar et al. 2006, Eq. (13)): packet number S_t and volume X_t + x_k S_t in cell k;
// and the deaths of class k are N_k sum_t b_t(k) S_t(n - 1). Then the diagonals and the rest as above.
template <class Scratch, class Place>
void aggregate_separable(const Population::Work& w, Scratch& sc, const double* N, int n,
                         const FixedPivotAggregation* fp, const CellAverageAggregation* ca, const Grid& g, double* dN,
                         double* out, Place&& place) {
  const auto& x = g.pivots();
  sc.mv.resize(size_t(5) * n);
  double* sum0 = sc.mv.data();        // per row: sum_t b_t(k) S_t(J(k))
  double* sum1 = sum0 + n;            // sum_t b_t(k) X_t(J(k))
  double* death = sum0 + 2 * n;       // sum_t b_t(k) S_t(n - 1)
  double* cs = sc.mv.data() + 3 * n;  // S_t, then X_t below (2 n)
  for (int k = 0; k < n; ++k) sum0[k] = sum1[k] = death[k] = 0.0;
  for (int t = 0; t < w.terms; ++t) {
    const double* a = w.ta.data() + size_t(t) * n;
    const double* b = w.tb.data() + size_t(t) * n;
    double* S = cs;
    double* X = cs + n;
    double s0 = 0.0, s1 = 0.0;
    for (int j = 0; j < n; ++j) {
      const double aN = a[j] * N[j];
      s0 += aN, s1 += aN * x[j];
      S[j] = s0, X[j] = s1;
    }
    for (int k = 0; k < n; ++k) {
      death[k] += b[k] * s0;
      const int J = w.prefix_end[k];
      if (J >= 0) sum0[k] += b[k] * S[J], sum1[k] += b[k] * X[J];
    }
  }
  if (fp) {
    const double* gap = w.inv_gap.data();
    for (int k = 0; k < n; ++k) {
      const double up = N[k] * sum1[k] * gap[k];
      dN[k] += N[k] * (sum0[k] - death[k]) - up;
      if (k + 1 < n) {
        dN[k + 1] += up;
      } else {
        out[kOutNumberAbove] += up;
        out[kOutVolumeAbove] += up * g.upper_virtual();
      }
    }
  } else {
    for (int k = 0; k < n; ++k) {
      dN[k] -= N[k] * death[k];
      sc.B[k] += N[k] * sum0[k];
      sc.V[k] += N[k] * (sum1[k] + x[k] * sum0[k]);
    }
  }
  aggregate_diagonals(w, sc, N, n, 0, fp, ca, g, dN, nullptr, place);
}

// The Jet copies of the tables, for evaluations that carry derivatives (sensitivities, AD Jacobians).
void make_jets(Population::Work& w) {
  if (w.jets) return;
  to_jets(w.Kh, w.Kh_jet), to_jets(w.A, w.A_jet), to_jets(w.BN, w.BN_jet), to_jets(w.BQ, w.BQ_jet);
  w.jets = true;
}

Population::Population() = default;
Population::~Population() = default;
Population::Population(Population&&) noexcept = default;
Population& Population::operator=(Population&&) noexcept = default;

template <class K>
Population::Plugin<K> Population::plugin(UnitSpec& s, Settings& st, const Registry<K>& reg, const std::string& name,
                                         const std::string& param_prefix, const std::string& setting_prefix) {
  Plugin<K> pl;
  if (name == kNone) return pl;
  pl.kernel = reg.create(name, st.where());
  pl.kernel->declare(st, setting_prefix);
  pl.first = static_cast<int>(s.params().size());
  for (ParamSpec spec : pl.kernel->params()) {
    spec.name = param_prefix + spec.name;
    if (s.param_index(spec.name) >= 0)
      throw ConfigError(st.where() + ": parameter '" + spec.name + "' of " + name +
                        " is declared twice in this unit (two mechanisms with the same parameter name)");
    s.add_param(std::move(spec));
  }
  pl.count = static_cast<int>(s.params().size()) - pl.first;
  for (int k = pl.first; k < pl.first + pl.count; ++k) kernel_params_.push_back(k);
  needs_ |= pl.kernel->needs();
  return pl;
}

void Population::declare(UnitSpec& s, Settings& st, std::shared_ptr<const Grid> grid, const PopulationOptions& o) {
  const auto& reg = registries();
  grid_ = std::move(grid);
  n_ = grid_->size();
  property_names_ = o.properties;
  if (properties() > kMaxProperties)
    throw std::logic_error("a population carries at most " + std::to_string(kMaxProperties) + " properties per class");
  outside_ = st.get_choice("outside", o.outside == Outside::kFold ? "fold" : "remove", {"fold", "remove"},
                           "particles leaving the grid: kept in the end class with their volume (fold, paper 001) "
                           "or removed and counted (remove)") == "fold"
                 ? Outside::kFold
                 : Outside::kRemove;
  const std::string agg =
      st.get_choice("aggregation", o.aggregation, with_none(reg.aggregation.names()), "aggregation kernel");
  agg_ = plugin(s, st, reg.aggregation, agg, o.agg_prefix, o.agg_settings);
  if (agg_.kernel) {
    agg_scheme_ = reg.aggregation_schemes.create(st.get_choice("aggregation_scheme", o.aggregation_scheme,
                                                               reg.aggregation_schemes.names(), "aggregation scheme"),
                                                 st.where());
    agg_scheme_->setup(*grid_);
  }
  const std::string sel =
      st.get_choice("breakage", o.breakage, with_none(reg.selection.names()), "breakage selection rate");
  sel_ = plugin(s, st, reg.selection, sel, o.sel_prefix, o.sel_settings);
  if (sel_.kernel) {
    frag_ = plugin(s, st, reg.fragments,
                   st.get_choice("fragments", o.fragments, reg.fragments.names(), "fragment distribution"),
                   o.frag_prefix, o.frag_settings);
    brk_scheme_ = reg.breakage_schemes.create(
        st.get_choice("breakage_scheme", o.breakage_scheme, reg.breakage_schemes.names(), "breakage scheme"),
        st.where());
  }
  const std::string gr =
      o.growth.empty() ? kNone : st.get_choice("growth", o.growth, with_none(reg.growth.names()), "growth law");
  growth_ = plugin(s, st, reg.growth, gr, o.growth_prefix, o.growth_settings);
  if (growth_.kernel) {
    growth_scheme_ = reg.growth_schemes.create(
        st.get_choice("growth_scheme", o.growth_scheme, reg.growth_schemes.names(), "growth scheme"), st.where());
    growth_scheme_->setup(*grid_);
  }
  field_index_.clear();
  for (int f = 0; f < kFields; ++f)
    if (needs_.field(static_cast<Field>(f))) field_index_.push_back(f);
}

std::string Population::aggregation_evaluation(const Work& w) const {
  return !agg_.kernel ? "none" : w.terms > 0 ? "separable" : w.matrices ? "matrices" : "pairs";
}

Population::WorkPtr Population::make_work() const { return WorkPtr(new Work()); }
void Population::WorkDeleter::operator()(Work* w) const { delete w; }

template <class T>
ClassState<T> Population::class_state(const State<T>& s) const {
  ClassState<T> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  cs.number = s.N;
  for (int f = 0; f < kFields; ++f) cs.fields[f] = s.fields[f];
  return cs;
}

void Population::configure(Work& w, const double* p, const std::string& where) const {
  ClassState<double> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  const std::pair<const KernelBase*, int> kernels[] = {{agg_.kernel.get(), agg_.first},
                                                       {sel_.kernel.get(), sel_.first},
                                                       {frag_.kernel.get(), frag_.first},
                                                       {growth_.kernel.get(), growth_.first}};
  for (const auto& [k, first] : kernels)
    if (k) k->check(cs, p + first, where);
  w.fresh = false;
  refresh(w, p);
}

// The matrices of Work::matrices from the pair table Kh (see there).
void Population::pair_matrices(Work& w, const ClassState<double>& cs, const double* p) const {
  const int n = n_;
  const auto* fp = dynamic_cast<const FixedPivotAggregation*>(agg_scheme_.get());
  const auto* ca = dynamic_cast<const CellAverageAggregation*>(agg_scheme_.get());
  w.matrices = (fp || ca) && agg_.kernel->n_features() == 0;
  w.terms = 0;
  if (!w.matrices) return;
  if (properties() == 0) {
    w.ta.assign(size_t(kMaxFactorTerms) * n, 0.0), w.tb.assign(size_t(kMaxFactorTerms) * n, 0.0);
    w.terms = agg_.kernel->factor_terms(cs, p, w.ta.data(), w.tb.data());
    if (w.terms > 0 && separable_tables(w, fp, ca)) return;
    w.terms = 0;
  }
  const size_t nn = size_t(n) * n;
  w.Km.assign(w.K.begin(), w.K.end());  // K is symmetric: row-major = column-major
  auto zero = [nn](std::vector<double>& m, bool used) { used ? m.assign(nn, 0.0) : m.clear(); };
  zero(w.Am, fp), zero(w.Bm, fp), zero(w.Fm, fp && properties() > 0), zero(w.Gm, fp && properties() > 0);
  zero(w.Cm, ca), zero(w.Vc, ca);
  size_t p0 = 0;
  for (int j = 0; j < n; p0 += n - j, ++j) {
    const int a = fp ? fp->run_first(j) : ca->run_first(j), b = fp ? fp->run_last(j) : ca->run_last(j);
    for (int k = a; k <= b; ++k) {
      const size_t pr = p0 + (k - j), at = size_t(k) * n + j;
      const double kh = w.Kh[pr];
      if (fp) {
        const auto& t = fp->target(pr);
        w.Am[at] = t.w_lo * kh, w.Bm[at] = t.w_hi * kh;
        if (!w.Fm.empty()) w.Fm[at] = t.f_lo * kh, w.Gm[at] = t.f_hi * kh;
      } else {
        w.Cm[at] = kh, w.Vc[at] = ca->volume(pr) * kh;
      }
    }
  }
  w.folded = fp && properties() == 0;
  if (w.folded) {
    for (size_t i = 0; i < nn; ++i) w.Am[i] -= w.Km[i];
    w.Km.clear();
  }
  const size_t nd = fp ? fp->diagonals().size() : ca->diagonals().size();
  w.rest.clear();
  p0 = 0;
  for (int j = 0; j < n; p0 += n - j, ++j) {
    const int a = fp ? fp->run_first(j) : ca->run_first(j), b = fp ? fp->run_last(j) : ca->run_last(j);
    for (int k = j; k < n; ++k) {
      const size_t d = k - j;
      const int last = d < nd ? (fp ? fp->diagonals()[d].last : ca->diagonals()[d].last) : -1;
      if ((a <= k && k <= b) || k <= last) continue;
      w.rest.push_back({p0 + d, {j, k}});
    }
  }
  w.Kd.assign(nd * n, 0.0);
  for (size_t d = 0; d < nd; ++d)
    for (int k = static_cast<int>(d); k < n; ++k) {
      const int j = k - static_cast<int>(d);
      w.Kd[d * n + k] = w.Kh[pair_index(j, k, n)];
    }
}

// Work::prefix_end, inv_gap, rest and Kd for a separable kernel: row k's prefix is the longest run of partners j = 0,
// 1, ... off the diagonals whose aggregates the scheme places like a run pair (fixed pivot: on k and k + 1, or on k
// and above the grid for the top class; cell average: in cell k); every other pair off the diagonals is in `rest`.
// False (use the matrices) if a prefix pair's table weights differ from the affine form the prefix sums assume.
bool Population::separable_tables(Work& w, const FixedPivotAggregation* fp, const CellAverageAggregation* ca) const {
  const int n = n_;
  const Grid& g = *grid_;
  auto pair = [n](int j, int k) { return pair_index(j, k, n); };
  const int nd = fp ? static_cast<int>(fp->diagonals().size()) : static_cast<int>(ca->diagonals().size());
  auto on_diagonal = [&](int j, int k) {
    const int d = k - j;
    return d < nd && k <= (fp ? fp->diagonals()[d].last : ca->diagonals()[d].last);
  };
  w.prefix_end.assign(n, -1);
  w.inv_gap.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const double gap = g.pivot_ext(k + 1) - g.pivot(k);
    w.inv_gap[k] = 1.0 / gap;
    int J = -1;
    for (int j = 0; j < k && !on_diagonal(j, k); ++j) {
      const size_t pr = pair(j, k);
      if (fp) {
        const auto& t = fp->target(pr);
        if (t.lo != k || t.hi != (k + 1 < n ? k + 1 : -1)) break;
        if (std::abs(t.w_hi - g.pivot(j) / gap) > 1e-12) return false;
      } else if (ca->cell(pr) != k) {
        break;
      }
      J = j;
    }
    w.prefix_end[k] = J;
  }
  w.rest.clear();
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k)
      if (j > w.prefix_end[k] && !on_diagonal(j, k)) w.rest.push_back({pair(j, k), {j, k}});
  w.Kd.assign(size_t(nd) * n, 0.0);
  for (int d = 0; d < nd; ++d)
    for (int k = d; k < n; ++k) w.Kd[size_t(d) * n + k] = w.Kh[pair(k - d, k)];
  w.Km.clear(), w.Am.clear(), w.Bm.clear(), w.Fm.clear(), w.Gm.clear(), w.Cm.clear(), w.Vc.clear();
  w.folded = false;
  return true;
}

// Re-evaluates the tables when a kernel parameter value changed since the last evaluation (a time-dependent input).
void Population::refresh(Work& w, const double* p) const {
  bool same = w.fresh && w.snapshot.size() == kernel_params_.size();
  for (size_t k = 0; same && k < kernel_params_.size(); ++k) same = w.snapshot[k] == p[kernel_params_[k]];
  if (same) return;
  w.snapshot.resize(kernel_params_.size());
  for (size_t k = 0; k < kernel_params_.size(); ++k) w.snapshot[k] = p[kernel_params_[k]];
  w.fresh = true;
  w.jets = false;
  ClassState<double> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  if (agg_.kernel) {
    w.K.resize(size_t(n_) * n_);
    agg_.kernel->factor(cs, p + agg_.first, w.K.data());
    pack_pairs(w.K, n_, w.Kh);
    pair_matrices(w, cs, p + agg_.first);
  }
  if (sel_.kernel) {
    w.A.resize(size_t(n_ + kOutsideRows) * n_);
    fragment_matrix(p + frag_.first, w.A);
    if (!sel_.kernel->state_dependent()) {
      w.S.resize(n_);
      sel_.kernel->evaluate(cs, p + sel_.first, w.S.data());
      breakage_tables(*grid_, w.A.data(), w.S.data(), w.BN, w.BQ);
    }
  }
}

// The fragment matrix depends on the fragment law's parameters only and costs O(n^2) quadratures: the last one
// built is kept (runs of a sweep or a calibration rarely change it).
void Population::fragment_matrix(const double* p, std::vector<double>& A) const {
  std::vector<double> key(p, p + frag_.count);
  {
    std::lock_guard<std::mutex> lock(frag_cache_->mutex);
    if (frag_cache_->valid && frag_cache_->key == key) {
      A = frag_cache_->A;
      return;
    }
  }
  brk_scheme_->build(*grid_, *frag_.kernel, p, A.data());
  std::lock_guard<std::mutex> lock(frag_cache_->mutex);
  frag_cache_->key = std::move(key);
  frag_cache_->A = A;
  frag_cache_->valid = true;
}

template <class T>
bool Population::fresh_tables(const Work&, const T* p, int first, int count) const {
  return has_derivative(p, first, count);
}

void Population::rates(Work& w, const State<double>& s, const Rates<double>& r) const {
  const FlushDenormals ftz;
  refresh(w, s.p);
  rates_t(w, s, r, true);
}

void Population::rates(Work& w, const State<Jet>& s, const Rates<Jet>& r) const {
  std::vector<double>& v = w.jinv;  // parameter values without derivatives, for the cached tables
  int np = 0;
  for (int k : kernel_params_) np = std::max(np, k + 1);
  v.resize(np);
  for (int k : kernel_params_) v[k] = s.p[k].a;
  refresh(w, v.data());
  make_jets(w);
  rates_t(w, s, r, true);
}

// The rates of every mechanism into work rows (class rows, then the outside rows), folded, then added to `r`.
template <class T>
void Population::rates_t(Work& w, const State<T>& s, const Rates<T>& r, bool fold) const {
  const int n = n_, P = properties(), no = outside_rows();
  auto& sc = w.scratch<T>();
  const ClassState<T> cs = class_state(s);
  const T* N = s.N;
  sc.rows.assign(n + no, T(0.0));
  sc.dq.assign(size_t(P) * n, T(0.0));
  T* dN = sc.rows.data();
  T* out = dN + n;
  T* dq = sc.dq.data();
  sc.pi.resize(size_t(P) * n);
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) sc.pi[size_t(p) * n + i] = s.q[p][i] / (N[i] + (s.floor ? s.floor[i] : T(0.0)));
  const T* pi = sc.pi.data();
  const auto& x = grid_->pivots();

  if (agg_.kernel) {
    const T* Kh;
    if constexpr (std::is_same_v<T, double>) {
      Kh = w.Kh.data();
    } else if (fresh_tables(w, s.p, agg_.first, agg_.count)) {
      sc.K.resize(size_t(n) * n);
      agg_.kernel->factor(cs, s.p + agg_.first, sc.K.data());
      pack_pairs(sc.K, n, sc.Kh);
      Kh = sc.Kh.data();
    } else {
      Kh = w.Kh_jet.data();
    }
    const int m = agg_.kernel->n_features();
    const T* E = nullptr;
    if (m > 0) {
      sc.phi.resize(size_t(n) * m);
      agg_.kernel->features(cs, s.p + agg_.first, sc.phi.data());
      sc.E.resize(pair_count(n));
      agg_.kernel->efficiencies(sc.phi.data(), n, s.p + agg_.first, sc.E.data());
      E = sc.E.data();
    }
    const auto* fp = dynamic_cast<const FixedPivotAggregation*>(agg_scheme_.get());
    const auto* ca = dynamic_cast<const CellAverageAggregation*>(agg_scheme_.get());
    if (ca) {
      sc.B.assign(n + 1, T(0.0));
      sc.V.assign(n + 1, T(0.0));
      sc.Q.assign(size_t(P) * (n + 1), T(0.0));
    } else {
      sc.up.assign(size_t(1 + P) * (n + 1), T(0.0));  // births the runs place on k + 1, added after the loop
    }
    sc.rate.resize(n);
    T* rt = sc.rate.data();
    // One aggregate event of the pair (j, k): places it through the scheme's table (the pairs outside the runs).
    auto place = [&](size_t pr, int j, int k, const T& rate) {
      if (fp) {
        const FixedPivotAggregation::Target& t = fp->target(pr);
        if (t.lo >= 0) dN[t.lo] += t.w_lo * rate;
        if (t.hi >= 0) {
          dN[t.hi] += t.w_hi * rate;
        } else {
          out[kOutNumberAbove] += t.w_hi * rate;
          out[kOutVolumeAbove] += t.f_hi * fp->volume(pr) * rate;
        }
        for (int p = 0; p < P; ++p) {
          const T carried = rate * (pi[size_t(p) * n + j] + pi[size_t(p) * n + k]);
          if (t.lo >= 0) dq[size_t(p) * n + t.lo] += t.f_lo * carried;
          if (t.hi >= 0)
            dq[size_t(p) * n + t.hi] += t.f_hi * carried;
          else
            out[out_property_above(p)] += t.f_hi * carried;
        }
      } else {
        const int c = ca->cell(pr);
        sc.B[c] += rate;
        sc.V[c] += ca->volume(pr) * rate;
        for (int p = 0; p < P; ++p)
          sc.Q[size_t(p) * (n + 1) + c] += rate * (pi[size_t(p) * n + j] + pi[size_t(p) * n + k]);
      }
    };
    bool by_matrices = false;
    if constexpr (std::is_same_v<T, double>) by_matrices = w.matrices && !E;
    if (by_matrices) {
      if constexpr (std::is_same_v<T, double>) {
        if (w.terms > 0)
          aggregate_separable(w, sc, N, n, fp, ca, *grid_, dN, out, place);
        else
          aggregate_by_matrices(w, sc, N, n, P, fp, ca, *grid_, dN, dq, place);
      }
    } else {
      // Row j of the pair triangle (partners k >= j, contiguous in the pair tables): the event rates in one
      // vectorizable pass, the deaths, then the births. Most partners place their aggregate on k and k + 1 (fixed
      // pivot) or keep it in cell k (cell average); those runs are plain array arithmetic (about 0.2 ns per pair
      // instead of 1-2 ns through the table), the rest goes through place().
      // With doubles, the pairs along the scheme's diagonals (near-equal partners) are stored by diagonal and summed
      // after the rows as vector loops (aggregate_diagonals), not placed one by one.
      int nd = 0;
      if constexpr (std::is_same_v<T, double>) {
        nd = static_cast<int>(fp ? fp->diagonals().size() : ca->diagonals().size());
        if (nd > 0) sc.diag.assign(size_t(nd) * n, 0.0);
      }
      auto on_diagonal = [&](int d, int k) {
        return d < nd && k <= (fp ? fp->diagonals()[d].last : ca->diagonals()[d].last);
      };
      size_t p0 = 0;  // pair (j, j)
      for (int j = 0; j < n; p0 += n - j, ++j) {
        if (is_empty(N[j])) continue;
        const T Nj = N[j];
        const T* kh = Kh + (p0 - j);  // kh[k]: pair (j, k)
        const int a = fp ? fp->run_first(j) : ca->run_first(j), b = fp ? fp->run_last(j) : ca->run_last(j);
        bool fused = false;
        if constexpr (std::is_same_v<T, double>) {
          if (fp) {
            const double* e = E ? E + (p0 - j) : nullptr;
            auto row = e ? (P == 1 ? fixed_pivot_row<true, true> : fixed_pivot_row<true, false>)
                         : (P == 1 ? fixed_pivot_row<false, true> : fixed_pivot_row<false, false>);
            row(*fp, p0, j, n, P, kh, e, N, pi, rt, dN, dq, sc.up.data());
            fused = true;
          }
        }
        if (!fused) {
          const T death = row_rates(kh, E ? E + (p0 - j) : nullptr, Nj, N, j, n, rt);
#pragma omp simd
          for (int k = j; k < n; ++k) dN[k] -= rt[k];
          dN[j] -= death;
          for (int p = 0; p < P; ++p) {
            const T* pp = pi + size_t(p) * n;
            T* dqp = dq + size_t(p) * n;
#pragma omp simd
            for (int k = j; k < n; ++k) dqp[k] -= rt[k] * pp[k];
            dqp[j] -= death * pp[j];
          }
        }
        for (int k = j; k < n; ++k) {
          if (k == a) k = b + 1;  // the run, below
          if (k >= n) break;
          if (on_diagonal(k - j, k)) {
            sc.diag[size_t(k - j) * n + k] = rt[k];
            continue;
          }
          if (!is_empty(N[k])) place(p0 + (k - j), j, k, rt[k]);
        }
        if (a > b || fused) continue;
        if (fp) {
          const double *wl = fp->w_lo() + (p0 - j), *wh = fp->w_hi() + (p0 - j);
          T* up = sc.up.data();
#pragma omp simd
          for (int k = a; k <= b; ++k) {
            dN[k] += wl[k] * rt[k];
            up[k + 1] += wh[k] * rt[k];
          }
          const double *fl = fp->f_lo() + (p0 - j), *fh = fp->f_hi() + (p0 - j);
          for (int p = 0; p < P; ++p) {
            const T* pp = pi + size_t(p) * n;
            T* dqp = dq + size_t(p) * n;
            T* upq = up + size_t(1 + p) * (n + 1);
            const T pj = pp[j];
#pragma omp simd
            for (int k = a; k <= b; ++k) {
              const T carried = rt[k] * (pj + pp[k]);
              dqp[k] += fl[k] * carried;
              upq[k + 1] += fh[k] * carried;
            }
          }
        } else {
          const double* vol = ca->volumes() + (p0 - j);
          T *B = sc.B.data(), *V = sc.V.data();
#pragma omp simd
          for (int k = a; k <= b; ++k) {
            B[k] += rt[k];
            V[k] += vol[k] * rt[k];
          }
          for (int p = 0; p < P; ++p) {
            const T* pp = pi + size_t(p) * n;
            T* Qp = sc.Q.data() + size_t(p) * (n + 1);
            const T pj = pp[j];
#pragma omp simd
            for (int k = a; k <= b; ++k) Qp[k] += rt[k] * (pj + pp[k]);
          }
        }
      }
      if constexpr (std::is_same_v<T, double>)
        if (nd > 0) aggregate_diagonals(w, sc, N, n, P, fp, ca, *grid_, dN, dq, place, sc.diag.data());
      if (fp) {
        for (int i = 0; i < n; ++i) dN[i] += sc.up[i];
        for (int p = 0; p < P; ++p)
          for (int i = 0; i < n; ++i) dq[size_t(p) * n + i] += sc.up[size_t(1 + p) * (n + 1) + i];
      }
    }
    if (ca) {
      // Each packet split on the side of its mean volume (Kumar et al. 2006, Eq. (15)); properties follow the volume.
      // A packet touches at most classes a and a + 1 and the outside rows: only those entries of `split` are
      // read and then cleared, so the loop costs O(n), not O(n^2).
      sc.split.assign(n + kOutsideRows, T(0.0));
      T* split = sc.split.data();
      for (int c = 0; c < n; ++c) {
        if (is_empty(sc.B[c])) continue;
        const int a = ca->side(*grid_, c, sc.B[c], sc.V[c]);
        const int lo = std::max(a, 0), hi = std::min(a + 1, n - 1);
        split_between(*grid_, a, sc.B[c], sc.V[c], split);
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
  }

  if (sel_.kernel) {
    // Paper 001, Eqs. (23), (25): dN/dt = A (S o N) = BN N; a property follows the volume of its parent's fragments.
    const T *BN, *BQ;
    if (sel_.kernel->state_dependent() || fresh_tables(w, s.p, sel_.first, sel_.count) ||
        fresh_tables(w, s.p, frag_.first, frag_.count)) {
      sc.S.resize(n);
      sel_.kernel->evaluate(cs, s.p + sel_.first, sc.S.data());
      const T* A;
      if (fresh_tables(w, s.p, frag_.first, frag_.count)) {
        sc.A.resize(size_t(n + kOutsideRows) * n);
        brk_scheme_->build(*grid_, *frag_.kernel, s.p + frag_.first, sc.A.data());
        A = sc.A.data();
      } else if constexpr (std::is_same_v<T, double>) {
        A = w.A.data();
      } else {
        A = w.A_jet.data();
      }
      breakage_tables(*grid_, A, sc.S.data(), sc.BN, sc.BQ);
      BN = sc.BN.data(), BQ = sc.BQ.data();
    } else if constexpr (std::is_same_v<T, double>) {
      BN = w.BN.data(), BQ = w.BQ.data();
    } else {
      BN = w.BN_jet.data(), BQ = w.BQ_jet.data();
    }
    sc.brk.resize(n + kOutsideRows);
    T* acc = sc.brk.data();  // class rows, then kNumberAbove, kVolumeAbove, kVolumeBelow (lined up with kOut*)
    table_times(BN, n + kOutsideRows, n, N, acc);
    for (int row = 0; row < n; ++row) dN[row] += acc[row];
    for (int k = 0; k < kOutsideRows; ++k) out[k] += acc[n + k];
    for (int p = 0; p < P; ++p) {
      table_times(BQ, n + 1, n, s.q[p], acc);  // row n: the property below the grid
      for (int row = 0; row < n; ++row) dq[size_t(p) * n + row] += acc[row];
      out[out_property_below(p)] += acc[n];
    }
  }

  if (growth_.kernel) {
    const int nf = n + 1, terms = growth_.kernel->terms();
    sc.shape.resize(size_t(terms) * nf);
    sc.amount.resize(terms);
    growth_.kernel->evaluate(growth_scheme_->face_diameters().data(), nf, s.p + growth_.first, sc.shape.data(),
                             sc.amount.data());
    const GrowthTerms<T> g{terms, sc.shape.data(), sc.amount.data(), growth_.kernel->volume_normalized()};
    sc.F.resize(nf);
    sc.donor.resize(nf);
    const T W = growth_scheme_->fluxes(N, g, sc.F.data(), sc.donor.data());
    // paper 003, Eqs. (7.32), (7.34): dN_i/dt = F_i - F_{i+1}; what crosses an end face leaves at its virtual pivot
    for (int f = 0; f < nf; ++f) {
      const T& F = sc.F[f];
      if (f > 0)
        dN[f - 1] -= F;
      else
        out[kOutVolumeBelow] -= F * grid_->lower_virtual();
      if (f < n)
        dN[f] += F;
      else
        out[kOutNumberAbove] += F, out[kOutVolumeAbove] += F * grid_->upper_virtual();
      const int d = sc.donor[f];
      if (d < 0) continue;
      for (int p = 0; p < P; ++p) {
        const T Fq = F * pi[size_t(p) * n + d];
        if (f > 0)
          dq[size_t(p) * n + f - 1] -= Fq;
        else
          out[out_property_below(p)] -= Fq;
        if (f < n)
          dq[size_t(p) * n + f] += Fq;
        else
          out[out_property_above(p)] += Fq;
      }
    }
    if (r.grown) *r.grown += W;
  }

  if (fold && outside_ == Outside::kFold) {
    dN[0] += out[kOutVolumeBelow] / x[0];
    dN[n - 1] += out[kOutVolumeAbove] / x[n - 1];
    for (int p = 0; p < P; ++p) {
      dq[size_t(p) * n] += out[out_property_below(p)];
      dq[size_t(p) * n + n - 1] += out[out_property_above(p)];
    }
  }
  for (int i = 0; i < n; ++i) r.dN[i] += dN[i];
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) r.dq[p][i] += dq[size_t(p) * n + i];
  if (r.outside)
    for (int k = 0; k < no; ++k) r.outside[k] += out[k];
}

int Population::input_cols() const { return n_ * (1 + properties() + static_cast<int>(field_index_.size())); }

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
  if (needs_.number || (sel_.kernel && sel_.kernel->state_dependent()))
    ad_jacobian(w, s, w.D);
  else
    analytic_jacobian(w, s, w.D);
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
  // Column by column (D is column-major), so that a dense sink's column (the unit's rows, mostly consecutive) is
  // written in order. Each sink entry receives its terms in the same order as row by row (several engine columns can
  // map to one sink column: the temperature field).
  for (int c = 0; c < C; ++c) {
    if (cols[c] < 0) continue;
    const double* d = &w.D[size_t(c) * R];
    const double sc = scales[c];
    if (double* col = sink.dense_column(cols[c])) {
      for (int r = 0; r < R; ++r)
        if (d[r] != 0.0 && rows[r] >= 0) col[rows[r]] += factors[r] * d[r] * sc;
    } else {
      for (int r = 0; r < R; ++r)
        if (d[r] != 0.0 && rows[r] >= 0) sink.add(rows[r], cols[c], factors[r] * d[r] * sc);
    }
  }
}

// d(rates)/d(N, q, fields) of the built-in mechanisms into D (rows: class numbers, properties, outside; columns: N,
// q, the fields read), before folding.
void Population::analytic_jacobian(Work& w, const State<double>& s, std::vector<double>& Dv) const {
  const int n = n_, P = properties(), C = input_cols(), nfr = static_cast<int>(field_index_.size());
  const size_t R = jacobian_rows();
  const auto& x = grid_->pivots();
  double* D = Dv.data();
  const size_t out0 = size_t(n) * (1 + P);
  auto rowN = [&](int i) { return size_t(i); };
  auto rowQ = [&](int p, int i) { return size_t(n) * (1 + p) + i; };
  auto rowO = [&](int k) { return out0 + k; };
  auto colQ = [&](int p, int i) { return n * (1 + p) + i; };
  auto colF = [&](int fi, int i) { return n * (1 + P) + fi * n + i; };
  auto add = [&](size_t r, int c, double v) { D[size_t(c) * R + r] += v; };  // column-major
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

  if (agg_.kernel) {
    const double* kp = s.p + agg_.first;
    const int mf = agg_.kernel->n_features();
    // Features and dphi_i/dfield_i: every class's field f seeded in direction f at once (phi_i reads class i only).
    std::vector<double> phi(size_t(n) * mf), G(size_t(n) * mf * std::max(nfr, 1), 0.0);
    if (mf > 0) {
      w.jf.resize(size_t(kFields) * n);
      ClassState<Jet> cj;
      cj.n = n, cj.volume = x.data(), cj.diameter = grid_->diameter_pivots().data();
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
    const auto* fp = dynamic_cast<const FixedPivotAggregation*>(agg_scheme_.get());
    const auto* ca = dynamic_cast<const CellAverageAggregation*>(agg_scheme_.get());
    if (ca) {
      w.dB.assign(size_t(n + 1) * C, 0.0);
      w.dV.assign(size_t(n + 1) * C, 0.0);
      w.dQ.assign(size_t(P) * (n + 1) * C, 0.0);
    }
    std::vector<double> B(n + 1, 0.0), V(n + 1, 0.0), Q(size_t(P) * (n + 1), 0.0);
    // The event's inputs: N_j, N_k and the fields of both partners.
    struct In {
      int col;
      double d;
    };
    In ev_buf[2 + 2 * kFields];
    int nev = 0;
    if (mf > 0) {
      const size_t pairs = size_t(n) * (n + 1) / 2;
      w.eff.resize(pairs), w.eff_da.resize(pairs * mf), w.eff_db.resize(pairs * mf);
      agg_.kernel->efficiency_gradients(phi.data(), n, kp, agg_.count, w.eff.data(), w.eff_da.data(), w.eff_db.data());
    }
    size_t pr = 0;
    for (int j = 0; j < n; ++j)
      for (int k = j; k < n; ++k, ++pr) {
        const double Kh = w.Kh[pr];
        double E = 1.0;
        const double* dEa = mf > 0 ? &w.eff_da[pr * mf] : nullptr;
        const double* dEb = mf > 0 ? &w.eff_db[pr * mf] : nullptr;
        if (mf > 0) E = w.eff[pr];
        const double beta = Kh * E, rate = beta * N[j] * N[k];
        nev = 0;
        ev_buf[nev++] = {j, beta * N[k]};
        ev_buf[nev++] = {k, beta * N[j]};
        for (int fi = 0; fi < nfr && mf > 0; ++fi) {
          double dj = 0, dk = 0;
          for (int c = 0; c < mf; ++c) {
            dj += dEa[c] * G[(size_t(j) * mf + c) * nfr + fi];
            dk += dEb[c] * G[(size_t(k) * mf + c) * nfr + fi];
          }
          ev_buf[nev++] = {colF(fi, j), Kh * N[j] * N[k] * dj};
          ev_buf[nev++] = {colF(fi, k), Kh * N[j] * N[k] * dk};
        }
        const In* ev_end = ev_buf + nev;
        // deaths of the partners, with their properties
        for (const In* e = ev_buf; e != ev_end; ++e) {
          add(rowN(j), e->col, -e->d);
          add(rowN(k), e->col, -e->d);
          for (int p = 0; p < P; ++p) {
            add(rowQ(p, j), e->col, -e->d * pi[size_t(p) * n + j]);
            add(rowQ(p, k), e->col, -e->d * pi[size_t(p) * n + k]);
          }
        }
        for (int p = 0; p < P; ++p)
          for (int i : {j, k}) {
            add(rowQ(p, i), i, -rate * dpi_dN[size_t(p) * n + i]);
            add(rowQ(p, i), colQ(p, i), -rate * dpi_dq[size_t(p) * n + i]);
          }
        if (fp) {
          const FixedPivotAggregation::Target& t = fp->target(pr);
          // number and property rows that receive the aggregate, with their weights on rate and on carried property
          struct Dest {
            int cls;  // -1: above
            double w, f;
          };
          const Dest dests[2] = {{t.lo, t.w_lo, t.f_lo}, {t.hi, t.w_hi, t.f_hi}};
          for (const Dest& d : dests) {
            if (d.w == 0.0 && d.f == 0.0) continue;
            for (const In* e = ev_buf; e != ev_end; ++e) {
              if (d.cls >= 0) {
                add(rowN(d.cls), e->col, d.w * e->d);
              } else {
                add(rowO(kOutNumberAbove), e->col, d.w * e->d);
                add(rowO(kOutVolumeAbove), e->col, d.f * fp->volume(pr) * e->d);
              }
              for (int p = 0; p < P; ++p) {
                const double carried = pi[size_t(p) * n + j] + pi[size_t(p) * n + k];
                add(d.cls >= 0 ? rowQ(p, d.cls) : rowO(out_property_above(p)), e->col, d.f * carried * e->d);
              }
            }
            for (int p = 0; p < P; ++p) {
              const size_t row = d.cls >= 0 ? rowQ(p, d.cls) : rowO(out_property_above(p));
              for (int i : {j, k}) {
                add(row, i, d.f * rate * dpi_dN[size_t(p) * n + i]);
                add(row, colQ(p, i), d.f * rate * dpi_dq[size_t(p) * n + i]);
              }
            }
          }
        } else {
          const int c = ca->cell(pr);
          const double v = ca->volume(pr);
          B[c] += rate;
          V[c] += v * rate;
          double* db = &w.dB[size_t(c) * C];
          double* dv = &w.dV[size_t(c) * C];
          for (const In* e = ev_buf; e != ev_end; ++e) db[e->col] += e->d, dv[e->col] += v * e->d;
          for (int p = 0; p < P; ++p) {
            const double carried = pi[size_t(p) * n + j] + pi[size_t(p) * n + k];
            Q[size_t(p) * (n + 1) + c] += rate * carried;
            double* dqc = &w.dQ[(size_t(p) * (n + 1) + c) * C];
            for (const In* e = ev_buf; e != ev_end; ++e) dqc[e->col] += carried * e->d;
            for (int i : {j, k}) {
              dqc[i] += rate * dpi_dN[size_t(p) * n + i];
              dqc[colQ(p, i)] += rate * dpi_dq[size_t(p) * n + i];
            }
          }
        }
      }
    if (ca) {
      SplitRow rows[3];
      for (int c = 0; c <= n; ++c) {
        const double* db = &w.dB[size_t(c) * C];
        const double* dv = &w.dV[size_t(c) * C];
        if (c == n) {  // beyond the top edge: leaves whole
          for (int col = 0; col < C; ++col) {
            add(rowO(kOutNumberAbove), col, db[col]);
            add(rowO(kOutVolumeAbove), col, dv[col]);
            for (int p = 0; p < P; ++p)
              add(rowO(out_property_above(p)), col, w.dQ[(size_t(p) * (n + 1) + n) * C + col]);
          }
          continue;
        }
        const int side = ca->side(*grid_, c, B[c], V[c]);
        const int m = split_rows(*grid_, side, rows);
        for (int r = 0; r < m; ++r) {
          const size_t row = rows[r].row < n ? rowN(rows[r].row) : rowO(rows[r].row - n);
          for (int col = 0; col < C; ++col)
            if (db[col] != 0.0 || dv[col] != 0.0)
              add(row, col, rows[r].d_number * db[col] + rows[r].d_volume * dv[col]);
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
            const double* dqc = &w.dQ[(size_t(p) * (n + 1) + c) * C];
            const size_t row = rr < n                   ? rowQ(p, rr)
                               : rr == n + kVolumeAbove ? rowO(out_property_above(p))
                                                        : rowO(out_property_below(p));
            for (int col = 0; col < C; ++col) {
              const double dvol = X * (rows[r].d_number * db[col] + rows[r].d_volume * dv[col]);
              const double d = (vol * dqc[col] + Qc * dvol) / V[c] - Qc * vol * dv[col] / (V[c] * V[c]);
              if (d != 0.0) add(row, col, d);
            }
          }
        }
      }
    }
  }

  if (sel_.kernel) {
    const double* BN = w.BN.data();
    const double* BQ = w.BQ.data();
    for (int row = 0; row < n + kOutsideRows; ++row)
      for (int k = row < n ? row : 0; k < n; ++k) {
        const double v = BN[size_t(row) * n + k];
        if (v != 0.0) add(row < n ? rowN(row) : rowO(row - n), k, v);
      }
    for (int p = 0; p < P; ++p)
      for (int row = 0; row <= n; ++row)
        for (int k = row < n ? row : 0; k < n; ++k) {
          const double v = BQ[size_t(row) * n + k];
          if (v != 0.0) add(row < n ? rowQ(p, row) : rowO(out_property_below(p)), colQ(p, k), v);
        }
  }

  if (growth_.kernel) {
    const int nf = n + 1, terms = growth_.kernel->terms();
    auto& sc = w.sd;
    sc.shape.resize(size_t(terms) * nf);
    sc.amount.resize(terms);
    growth_.kernel->evaluate(growth_scheme_->face_diameters().data(), nf, s.p + growth_.first, sc.shape.data(),
                             sc.amount.data());
    const GrowthTerms<double> g{terms, sc.shape.data(), sc.amount.data(), growth_.kernel->volume_normalized()};
    sc.F.resize(nf);
    sc.donor.resize(nf);
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
