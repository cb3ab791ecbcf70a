// What the two built-in aggregation schemes (fixed_pivot.hpp, cell_average.hpp) share: on any grid most pairs place
// their aggregate like their neighbours do, so the pair triangle splits into
//   * runs: the partners k of class j in [run_first(j), run_last(j)] whose aggregates land on k and k + 1 (fixed
//     pivot) or stay in cell k (cell average), summed as plain array arithmetic (or, for a size-only kernel, as
//     lower-triangular matrix-vector products, or for a separable one as prefix sums);
//   * diagonals: near-equal partners (k - d, k), placed with one shift and one set of weights per diagonal on a
//     geometric grid, summed as vector loops over k;
//   * the rest (the top of the grid, irregular grids), placed one by one through the scheme's pair table.
// The functions are templates over the scheme S (FixedPivotAggregation or CellAverageAggregation), instantiated for
// both in pair_rows.cpp and pair_matrices.cpp. RunLayout depends on the grid only (built in the scheme's setup());
// RunTables on the kernel's values (rebuilt on a parameter change) and holds the work arrays of one run.
#pragma once
#include <type_traits>
#include <utility>
#include <vector>

#include "discretization/aggregation_scheme.hpp"
#include "discretization/redistribution.hpp"

namespace granuflow::kernels {

class FixedPivotAggregation;
class CellAverageAggregation;

using PairList = std::vector<std::pair<size_t, std::pair<int, int>>>;  // (pair, (j, k))

struct RunLayout {
  // Separable size-only kernel without carried properties (AggregationKernel::factor_terms): K_jk = sum_t a_t(j)
  // b_t(k). Row k's run partners are then a prefix j <= J(k) (aggregates placed on k and k + 1 with w_hi = x_j /
  // (x_{k+1} - x_k), affine in x_j, or kept in cell k), so their births and all deaths are prefix sums: O(n) per term.
  bool separable = false;        // false: a prefix pair's weights differ from the affine form (use the matrices)
  std::vector<int> prefix_end;   // J(k); -1: no prefix
  std::vector<double> inv_gap;   // fixed pivot: 1 / (x_{k+1} - x_k), x_n the virtual pivot above the grid
  PairList rest_separable;       // pairs on neither a prefix nor a diagonal
  PairList rest_matrices;        // pairs on neither a run nor a diagonal
  std::vector<size_t> rest_row;  // row j's pairs in rest_matrices: [rest_row[j], rest_row[j + 1])
};

struct RunTables : AggregationScheme::Tables {
  // Size-only kernels (no per-pair efficiency): the pair sums as matrix products over row-major n x n matrices,
  // rows = the class whose rate is formed. Km: the full symmetric K (deaths: N_k (K N)_k). For the pairs of the
  // scheme's runs (the larger partner k keeps, or moves to k + 1, the aggregate): fixed pivot A (w_lo h K, births on
  // k), Bm (w_hi h K, births on k + 1), F, G (the same with the volume fractions, for carried properties); cell
  // average C (h K, events into cell k) and Vc ((x_j + x_k) h K, their volume). Empty when not used.
  bool matrices = false;
  bool folded = false;  // fixed pivot, no properties: Am holds A - K (births on k less all deaths), Km unused
  std::vector<double> Km, Am, Bm, Fm, Gm, Cm, Vc;
  std::vector<double> Kd;      // h K of the pairs (k - d, k) at [d n + k], for the scheme's diagonals
  int terms = 0;               // separable form (RunLayout): number of terms, 0 when not used
  std::vector<double> ta, tb;  // a and b (terms x n)
  template <class T>
  struct Scratch {
    std::vector<T> B, V, Q, up, rate, mv, split, diag;
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  // Analytic Jacobian of the cell average: the packets (B, V, Q per cell) and their derivatives (n + 1 rows of C).
  std::vector<double> jB, jV, jQ, dB, dV, dQ;
  const PairList& rest(const RunLayout& L) const { return terms > 0 ? L.rest_separable : L.rest_matrices; }
};

template <class S>
inline constexpr bool kFixedPivot = std::is_same_v<S, FixedPivotAggregation>;

template <class S>
void build_run_layout(const S& s, const Grid& g, RunLayout& L);
template <class S>
void refresh_run_tables(const S& s, RunTables& t, const AggregationTableInputs& in);
template <class S>
std::string run_evaluation(const RunTables& t);
// The rates of a run scheme: the size-only forms in doubles (pair_matrices.cpp), else the rows (pair_rows.cpp).
template <class S, class T>
void run_rates(const S& s, RunTables& t, const AggregationArgs<T>& a);
template <class S, class T>
void aggregate_rows(const S& s, RunTables& t, const AggregationArgs<T>& a);
template <class S>
void aggregate_by_matrices(const S& s, RunTables& t, const AggregationArgs<double>& a);
template <class S>
void aggregate_separable(const S& s, RunTables& t, const AggregationArgs<double>& a);
// The pairs along the scheme's diagonals, their event rates `stored` + d n when given (a kernel with per-pair
// efficiencies, whose row loop formed them), else h K N_{k-d} N_k from RunTables::Kd; then, without `stored`, the
// rest one by one.
template <class S>
void aggregate_diagonals(const S& s, RunTables& t, const AggregationArgs<double>& a, const double* stored = nullptr);

// The hooks of AggregationScheme that the run schemes share: their tables are RunTables, their sums the functions
// above; S provides the pair tables (target() or cell()), the runs, the diagonals and the Jacobian's hooks.
template <class S>
class RunScheme : public AggregationScheme {
 public:
  std::unique_ptr<Tables> make_tables() const override { return std::make_unique<RunTables>(); }
  void refresh(Tables& t, const AggregationTableInputs& in) const override {
    refresh_run_tables(self(), static_cast<RunTables&>(t), in);
  }
  std::string evaluation(const Tables& t) const override { return run_evaluation<S>(static_cast<const RunTables&>(t)); }
  void rates(Tables& t, const AggregationArgs<double>& args) const override {
    run_rates(self(), static_cast<RunTables&>(t), args);
  }
  void rates(Tables& t, const AggregationArgs<Jet>& args) const override {
    run_rates(self(), static_cast<RunTables&>(t), args);
  }
  const RunLayout& layout() const { return layout_; }

 protected:
  RunLayout layout_;  // built by S::setup() with build_run_layout()

 private:
  const S& self() const { return static_cast<const S&>(*this); }
};

// One aggregate event of the pair pr = (j, k) at `rate`, placed through the scheme's pair table (the pairs off the
// runs and diagonals): fixed pivot on its targets, cell average into its cell's packet.
template <class S, class T>
inline void place_pair(const S& s, RunTables::Scratch<T>& sc, const AggregationArgs<T>& a, size_t pr, int j, int k,
                       const T& rate) {
  const int n = a.n, P = a.P;
  const T* pi = a.pi;
  if constexpr (kFixedPivot<S>) {
    T *dN = a.dN, *dq = a.dq, *out = a.out;
    const auto& t = s.target(pr);
    if (t.lo >= 0) dN[t.lo] += t.w_lo * rate;
    if (t.hi >= 0) {
      dN[t.hi] += t.w_hi * rate;
    } else {
      out[kOutNumberAbove] += t.w_hi * rate;
      out[kOutVolumeAbove] += t.f_hi * s.volume(pr) * rate;
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
    const int c = s.cell(pr);
    sc.B[c] += rate;
    sc.V[c] += s.volume(pr) * rate;
    for (int p = 0; p < P; ++p) sc.Q[size_t(p) * (n + 1) + c] += rate * (pi[size_t(p) * n + j] + pi[size_t(p) * n + k]);
  }
}

}  // namespace granuflow::kernels
