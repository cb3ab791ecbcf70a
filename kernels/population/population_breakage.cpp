// Breakage in the population engine (paper 001, Eqs. (23), (25)): dN/dt = A (S o N) = BN N with the scheme's fragment
// matrix A (discretization/breakage_scheme.hpp) and the selection rates S folded in; a property follows the volume of
// its parent's fragments (BQ). Its rates and its (constant) Jacobian.
#include <Eigen/Dense>
#include <type_traits>

#include "population/population_work.hpp"

namespace granuflow::kernels {

namespace {
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

}  // namespace

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

template void breakage_tables<double>(const Grid&, const double*, const double*, std::vector<double>&,
                                      std::vector<double>&);
template void breakage_tables<Jet>(const Grid&, const Jet*, const Jet*, std::vector<Jet>&, std::vector<Jet>&);

// The tables of the cached parameter values, or rebuilt from the parameters' Jets when they carry derivatives or the
// selection rate reads the state.
template <class T>
void Population::breakage_rates(Work& w, const State<T>& s, const ClassState<T>& cs, T* dN, T* dq, T* out) const {
  const int n = n_, P = properties();
  auto& sc = w.scratch<T>();
  const T* N = s.N;
  // Paper 001, Eqs. (23), (25): dN/dt = A (S o N) = BN N; a property follows the volume of its parent's fragments.
  const T *BN, *BQ;
  const bool state = sel_.kernel->state_dependent();
  const bool fresh_sel = fresh_tables(w, s.p, sel_.first, sel_.count);
  const bool fresh_frag = fresh_tables(w, s.p, frag_.first, frag_.count);
  bool kept = false;  // Jet tables the last call built from these very parameter Jets (Work::sel_params)
  if constexpr (std::is_same_v<T, Jet>) {
    if (!state && (fresh_sel || fresh_frag)) {
      const bool same_sel = same_parameters(w.sel_params, s.p, sel_.first, sel_.count);
      const bool same_frag = same_parameters(w.frag_params, s.p, frag_.first, frag_.count);  // both memos kept
      kept = same_sel && same_frag;
    }
  }
  if (kept) {
    BN = sc.BN.data(), BQ = sc.BQ.data();
  } else if (state || fresh_sel || fresh_frag) {
    sc.S.resize(n);
    sel_.kernel->evaluate(cs, s.p + sel_.first, sc.S.data());
    const T* A;
    if (fresh_frag) {
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
template void Population::breakage_rates<double>(Work&, const State<double>&, const ClassState<double>&, double*,
                                                 double*, double*) const;
template void Population::breakage_rates<Jet>(Work&, const State<Jet>&, const ClassState<Jet>&, Jet*, Jet*, Jet*) const;

// d(rates)/dN and d(rates)/dq: the tables themselves (a selection rate that reads the state goes through AD).
// `local`: a class row's own entry only (fragments of class k that stay in k); nothing of the outside rows.
void Population::breakage_jacobian(const Work& w, const PopulationJacobian& J, bool local) const {
  const int n = n_, P = properties();
  const double* BN = w.BN.data();
  const double* BQ = w.BQ.data();
  for (int row = 0; row < (local ? n : n + kOutsideRows); ++row)
    for (int k = row < n ? row : 0; k < (local ? row + 1 : n); ++k) {
      const double v = BN[size_t(row) * n + k];
      if (v != 0.0) J.add(row < n ? J.rowN(row) : J.rowO(row - n), k, v);
    }
  for (int p = 0; p < P; ++p)
    for (int row = 0; row < (local ? n : n + 1); ++row)
      for (int k = row < n ? row : 0; k < (local ? row + 1 : n); ++k) {
        const double v = BQ[size_t(row) * n + k];
        if (v != 0.0) J.add(row < n ? J.rowQ(p, row) : J.rowO(out_property_below(p)), J.colQ(p, k), v);
      }
}

}  // namespace granuflow::kernels
