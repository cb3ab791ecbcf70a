// Internal to the population engine (population*.cpp): the per-run Work, and the helpers its files share.
#pragma once
#include <vector>
#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include "population/population.hpp"

namespace granuflow::kernels {

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

// Everything one run of a population computes: the tables that depend on parameters only (refreshed when a
// parameter value changes; the aggregation scheme's own in `agg`), and the work arrays of the rates and the Jacobian.
struct Population::Work {
  std::vector<double> snapshot;  // kernel parameter values of the tables
  bool fresh = false;            // the tables were computed for `snapshot`
  std::vector<double> K, S, A;   // beta factors (n x n), selection rates (n), breakage matrix ((n + 3) x n)
  std::vector<Jet> A_jet;
  bool jets = false;  // the *_jet copies match the tables (made when a Jet evaluation first needs them)
  // Per pair j <= k (row-major upper triangle) h K_jk, h = 1/2 for like pairs: the event rate is Kh E N_j N_k.
  std::vector<double> Kh;
  std::vector<Jet> Kh_jet;
  std::unique_ptr<AggregationScheme::Tables> agg;  // the scheme's tables of the kernel's values, and its work arrays
  // Breakage with the selection rates folded in: BN = A diag(S) ((n + 3) x n) moves numbers, BQ = (x_r / x_k) BN
  // ((n + 1) x n: class rows, then the volume below) moves a property with its parent's share of volume.
  std::vector<double> BN, BQ;
  std::vector<Jet> BN_jet, BQ_jet;
  // The parameters (values and derivatives) the Jet scratch's Kh and BN, BQ were last built from when they carry
  // derivatives (a sensitivity run's residuals): the tables depend on the sizes and those parameters only, so the
  // next evaluation with the same Jets reuses them instead of rebuilding h K and the breakage tables per call.
  std::vector<Jet> kh_params, sel_params, frag_params;
  template <class T>
  struct Scratch {
    std::vector<T> K, Kh, S, A, BN, BQ, phi, E, pi, shape, amount, F, rows, dq, brk;
    std::vector<int> donor;
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  // Jacobian work
  std::vector<double> D, dF, jinv, map_factors, map_scales;
  std::vector<int> map_rows, map_cols;
  struct RowRun {
    int first, len, row;  // engine rows first .. first+len-1 map to the unit's rows row .. row+len-1
  };
  std::vector<RowRun> map_runs;
  std::vector<Jet> jp, jN, jq, jf, jphi;
  std::vector<double> eff, eff_da, eff_db;  // analytic Jacobian: E and dE/dphi of every pair
  std::vector<PairEvent> events;            // the events of one row of the pair triangle, and their inputs
  std::vector<PairEvent::Input> inputs;
  // Class-local Jacobian (aggregation_local_jacobian): per pair what stays in the larger partner's class, from the
  // scheme once (0: not asked yet, 1: the scheme gave them, -1: it cannot); per class the sums of its own terms.
  std::vector<AggregationScheme::LocalBirths> local_births;
  int local_births_state = 0;
  std::vector<double> local_sums;
  // The pair terms' entries of a class-local Jacobian, per input column c (N, then q) and row q (0: its class's
  // number, 1 + p: property p), before growth adds its own: what the unit reports left out (JacobianSink::left_out).
  std::vector<double> local_kept;
};

// h K per pair, row-major upper triangle.
template <class T>
void pack_pairs(const std::vector<T>& K, int n, std::vector<T>& Kh) {
  Kh.resize(pair_count(n));
  size_t q = 0;
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k, ++q) Kh[q] = (j == k ? 0.5 : 1.0) * K[size_t(j) * n + k];
}

// BN = A diag(S), BQ = (x_r / x_k) BN over the class rows and the volume-below row (population_breakage.cpp).
template <class T>
void breakage_tables(const Grid& g, const T* A, const T* S, std::vector<T>& BN, std::vector<T>& BQ);

// Whether p[first, first + count) equals `memo` in values and derivatives; if not, `memo` becomes a copy of it.
bool same_parameters(std::vector<Jet>& memo, const Jet* p, int first, int count);

// Whether a kernel's parameters carry derivatives (a Jet evaluation then rebuilds its tables from them).
inline bool has_derivative(const double*, int, int) { return false; }
inline bool has_derivative(const Jet* p, int first, int count) {
  for (int k = first; k < first + count; ++k)
    if (!p[k].v.isZero()) return true;
  return false;
}

// The Jet copies of the tables, for evaluations that carry derivatives (sensitivities, AD Jacobians).
void make_jets(Population::Work& w);

}  // namespace granuflow::kernels
