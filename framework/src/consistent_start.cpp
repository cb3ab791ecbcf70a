#include "consistent_start.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "eigen_linear_solver.hpp"

namespace granuflow::detail {
namespace {

constexpr int kMaxIterations = 20;  // IDACalcIC takes over beyond
constexpr int kMaxHalvings = 5;     // of a correction whose residual the units refuse (a step out of their domain)
// Converged when the last correction's weighted RMS norm is below this: with Newton's quadratic rate the error left
// is of its square, far below IDACalcIC's own test (0.0033 in the same norm).
constexpr double kTolerance = 1e-4;
constexpr double kSlowRate = 0.25;  // a correction shrinking less than this asks for a fresh Jacobian

}  // namespace

int consistent_start(DaeSystem& sys, JacobianCache& cache, double t, const double* ewt, double* y, double* yp,
                     const double* j0) {
  const int n = sys.size();
  std::vector<double> jac(size_t(n) * n), r(n);
  if (j0)
    std::copy(j0, j0 + size_t(n) * n, jac.begin());
  else
    sys.jacobian(t, y, yp, 0.0, jac.data(), nullptr);
  if (cache.reusable < 0) check_contract(sys, t, y, yp, cache);
  if (cache.reusable != 1) return 0;
  const std::vector<double> id = sys.differential_id();
  std::vector<int> alg;
  for (int i = 0; i < n; ++i)
    if (id[i] == 0.0) alg.push_back(i);
  const int na = static_cast<int>(alg.size());
  const std::vector<double> y0(y, y + n);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  auto factor = [&] {
    Eigen::MatrixXd block(na, na);
    for (int j = 0; j < na; ++j)
      for (int i = 0; i < na; ++i) block(i, j) = jac[size_t(alg[j]) * n + alg[i]];
    lu.compute(block);
    const auto d = lu.matrixLU().diagonal();
    return d.allFinite() && (na == 0 || d.cwiseAbs().minCoeff() > 0.0);
  };
  auto give_up = [&] {
    std::copy(y0.begin(), y0.end(), y);
    return 0;
  };
  if (!factor()) return give_up();
  if (sys.residual(t, y, yp, r.data()) != Status::kOk) return give_up();
  Eigen::VectorXd delta(na), ra(na);
  double last = 0.0;
  bool converged = na == 0;
  for (int it = 0; it < kMaxIterations && !converged; ++it) {
    for (int i = 0; i < na; ++i) ra[i] = r[alg[i]];
    delta = -lu.solve(ra);
    if (!delta.allFinite()) return give_up();
    double sum = 0.0;
    for (int i = 0; i < na; ++i) sum += std::pow(delta[i] * ewt[alg[i]], 2);
    const double norm = std::sqrt(sum / n);  // over every state, as the integrator measures
    // Apply the correction, halved while the units refuse the state it leads to.
    double scale = 2.0;
    Status s = Status::kRecoverable;
    for (int h = 0; h <= kMaxHalvings && s != Status::kOk; ++h) {
      scale *= 0.5;
      for (int i = 0; i < na; ++i) y[alg[i]] += scale * delta[i];
      s = sys.residual(t, y, yp, r.data());
      if (s != Status::kOk)
        for (int i = 0; i < na; ++i) y[alg[i]] -= scale * delta[i];
    }
    if (s != Status::kOk) return give_up();
    converged = scale == 1.0 && norm <= kTolerance;
    if (!converged && it > 0 && norm > kSlowRate * last) {  // chord iterations stalled: Jacobian of this iterate
      sys.jacobian(t, y, yp, 0.0, jac.data(), nullptr);
      if (!factor()) return give_up();
    }
    last = norm;
  }
  if (!converged) return give_up();
  // r is the residual at the final y: y'_d - f_d(y) on the differential rows
  for (int i = 0; i < n; ++i)
    if (id[i] != 0.0) yp[i] -= r[i];
  // The integrator's first Newton matrix is evaluated afresh: the last one here may be from an earlier iterate, and
  // handing it on changed the headline scene's first steps and its results by up to 2e-5 relative (within the
  // tolerance, but results users compare against should not move for a faster start).
  cache.valid = false;
  for (int i : cache.differential) jac[size_t(i) * n + i] += 1.0;  // the structure of a Newton matrix, cj > 0
  return eigen_dense_block_for(jac.data(), n);
}

}  // namespace granuflow::detail
