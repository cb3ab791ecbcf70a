// The assembled DAE F(t, y, y', p) = 0 of a finalized flowsheet: residual, exact Jacobian dF/dy + cj dF/dy'
// (per unit: the unit's analytic Jacobian if it supplies one, else forward AD over its local variables),
// sensitivity residuals for named parameters, initial values, and per-state metadata for the solvers.
#pragma once
#include <string>
#include <unordered_map>
#include <vector>

#include "granuflow/flowsheet.hpp"

namespace granuflow {

// Compressed-sparse-column pattern of the Jacobian (union of the units' blocks).
struct SparsityPattern {
  int n = 0;
  std::vector<int> col_ptr;  // size n + 1
  std::vector<int> row_idx;  // size nnz, sorted within a column
  int nnz() const { return static_cast<int>(row_idx.size()); }
};

class DaeSystem {
 public:
  // Calls configure() of every unit with the current parameters. The flowsheet must be finalized and must
  // outlive this object; parameter changes need a new DaeSystem (cheap) or reconfigure().
  explicit DaeSystem(Flowsheet& fs);
  void reconfigure();

  int size() const { return n_; }
  const Flowsheet& flowsheet() const { return fs_; }

  // Inputs with step interpolation are held at their value at the start of the current segment, so the
  // integrator never sees a jump inside a segment.
  void set_segment_start(double t) { segment_start_ = t; }

  Status residual(double t, const double* y, const double* yp, double* r);
  // Dense column-major n x n (ld = n) when `dense` != nullptr, else values in `pattern()` order.
  void jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse_values);
  const SparsityPattern& pattern() const { return pattern_; }

  // Sensitivity residuals r_k = F_y s_k + F_y' s'_k + F_p e_{p_k} for global parameter ids `params`.
  Status sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                       const double* const* yS, const double* const* ypS, double* const* rS);

  void initial_values(std::vector<double>& y0) const;
  void initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const;
  std::vector<double> differential_id() const;  // 1 differential, 0 algebraic
  std::vector<double> scales() const;
  void report(double t, const double* y, const double* yp, double* out);
  // Unit and state name of a global row, for error messages.
  std::string describe_row(int row) const;

  long residual_count() const { return n_res_; }
  long jacobian_count() const { return n_jac_; }

 private:
  void fill_params(double t);
  void seed(int id, int u, size_t slot, std::vector<Jet>& pj) const;
  template <class T>
  void params_as(int unit, std::vector<T>& out) const;

  Flowsheet& fs_;
  int n_;
  double segment_start_ = 0.0;
  std::vector<std::vector<double>> pvals_;   // per unit, at the last fill time
  std::vector<std::vector<int>> local_cols_; // per unit: global columns its rows depend on
  std::vector<std::vector<int>> block_pos_;  // per unit: row-major [local row][local col] -> position in sparse values
  std::vector<std::unordered_map<int, int>> col_map_;  // per unit: global column -> local column
  SparsityPattern pattern_;
  std::vector<Jet> xj_, xdj_, rj_;
  std::vector<double> rbuf_;
  long n_res_ = 0, n_jac_ = 0;
};

}  // namespace granuflow
