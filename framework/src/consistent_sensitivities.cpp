#include "consistent_sensitivities.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <string>

#include "granuflow/errors.hpp"

namespace granuflow::detail {

void consistent_sensitivities(DaeSystem& sys, bool dense, double t, const double* y, const double* yp,
                              const std::vector<int>& params, double* const* yS, double* const* ypS) {
  const int n = sys.size();
  const size_t np = params.size();
  if (np == 0) return;
  const std::vector<double> id = sys.differential_id();
  // Right-hand sides: -(F_y(:, differential) s_diff + F_p e_k), the sensitivity residual with the unknowns at 0.
  std::vector<std::vector<double>> s0(np, std::vector<double>(n)), sp0(np, std::vector<double>(n, 0.0)),
      rs(np, std::vector<double>(n));
  std::vector<const double*> ps(np), pps(np);
  std::vector<double*> prs(np);
  for (size_t k = 0; k < np; ++k) {
    for (int i = 0; i < n; ++i) s0[k][i] = id[i] > 0 ? yS[k][i] : 0.0;
    ps[k] = s0[k].data(), pps[k] = sp0[k].data(), prs[k] = rs[k].data();
  }
  if (sys.sens_residual(t, y, yp, params, ps.data(), pps.data(), prs.data()) != Status::kOk)
    throw SolverError(
        "consistent initial sensitivities: the sensitivity residual failed at t = " + std::to_string(t) + " s", t, "",
        0.0);
  Eigen::MatrixXd rhs(n, np);
  for (size_t k = 0; k < np; ++k)
    for (int i = 0; i < n; ++i) rhs(i, k) = -rs[k][i];
  auto singular = [t] {
    return SolverError("consistent initial sensitivities: singular matrix [F_y(:, alg) | F_y'(:, diff)] at t = " +
                           std::to_string(t) + " s (is the DAE index 1?)",
                       t, "", 0.0);
  };
  Eigen::MatrixXd u;
  if (dense) {
    Eigen::MatrixXd j0(n, n), j1(n, n);
    sys.jacobian(t, y, yp, 0.0, j0.data(), nullptr);  // column-major, ld = n
    sys.jacobian(t, y, yp, 1.0, j1.data(), nullptr);
    Eigen::MatrixXd m(n, n);
    for (int c = 0; c < n; ++c)
      m.col(c) = id[c] > 0 ? Eigen::VectorXd(j1.col(c) - j0.col(c)) : Eigen::VectorXd(j0.col(c));
    Eigen::PartialPivLU<Eigen::MatrixXd> lu(m);
    u = lu.solve(rhs);
  } else {
    const SparsityPattern& pat = sys.pattern();
    std::vector<double> v0(pat.nnz()), v1(pat.nnz());
    sys.jacobian(t, y, yp, 0.0, nullptr, v0.data());
    sys.jacobian(t, y, yp, 1.0, nullptr, v1.data());
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(pat.nnz());
    for (int c = 0; c < pat.n; ++c)
      for (int q = pat.col_ptr[c]; q < pat.col_ptr[c + 1]; ++q)
        trip.emplace_back(pat.row_idx[q], c, id[c] > 0 ? v1[q] - v0[q] : v0[q]);
    Eigen::SparseMatrix<double> m(n, n);
    m.setFromTriplets(trip.begin(), trip.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
    lu.compute(m);
    if (lu.info() != Eigen::Success) throw singular();
    u = lu.solve(rhs);
  }
  if (!u.allFinite()) throw singular();  // PartialPivLU does not report a zero pivot: never pass NaN on to IDAS
  for (size_t k = 0; k < np; ++k)
    for (int i = 0; i < n; ++i) {
      if (id[i] > 0) {
        ypS[k][i] = u(i, k);
      } else {
        yS[k][i] = u(i, k);
        ypS[k][i] = 0.0;
      }
    }
}

}  // namespace granuflow::detail
