// The linear solvers of the Newton iterations: the iterative one (solver.linear_solver: gmres, GMRES on
// difference-quotient Jacobian-vector products with the block preconditioner of DaeSystem) gives the answer of the
// direct ones on flowsheets built for those (units without their own preconditioner get their exact own block), and
// says what it cannot do. The dense solver factors independent groups of states separately and gives the whole
// matrix's answer.
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "eigen_linear_solver.hpp"
#include "granuflow/errors.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

// Every state at the last output time, run with `solver` (and the integrator `method`).
SimResult run(Scene& s, const std::string& solver, const std::string& method = "auto") {
  SimOptions o = s.options;
  o.linear_solver = parse_linear_solver(solver);
  o.method = parse_method(method);
  return simulate(*s.flowsheet, o);
}

void expect_same_states(const SimResult& a, const SimResult& b, double rel) {
  const size_t n = a.state_names.size(), last = a.t.size() - 1;
  ASSERT_EQ(n, b.state_names.size());
  double scale = 0;
  for (size_t k = 0; k < n; ++k) scale = std::max(scale, std::abs(b.y[last * n + k]));
  for (size_t k = 0; k < n; ++k)
    EXPECT_NEAR(a.y[last * n + k], b.y[last * n + k], rel * std::max(std::abs(b.y[last * n + k]), 1e-6 * scale))
        << a.state_names[k];
}

TEST(LinearSolvers, GmresGivesTheDirectAnswerOnAFlowsheetOfSeveralUnits) {
  Scene s = scene_from_file("flowsheets/demo_tanks.yaml");
  const SimResult g = run(s, "gmres"), d = run(s, "dense");
  EXPECT_EQ(g.stats.linear_solver.rfind("gmres", 0), 0u);
  EXPECT_GT(g.stats.linear_iterations, 0);
  EXPECT_GT(g.stats.preconditioner_setups, 0);
  EXPECT_EQ(d.stats.linear_iterations, 0);
  expect_same_states(g, d, 1e-6);
}

// An ODE flowsheet on both BDF integrators: IDAS, and CVODES (whose Newton matrix I - gamma df/dy takes the DAE
// preconditioner at cj = 1 / gamma).
TEST(LinearSolvers, GmresGivesTheDirectAnswerForAPopulationOnIdasAndCvodes) {
  Scene s = scene_from_file("flowsheets/pbm_constant_kernel.yaml");
  for (const char* method : {"ida", "bdf"}) {
    SCOPED_TRACE(method);
    const SimResult g = run(s, "gmres", method), d = run(s, "dense", method);
    EXPECT_EQ(g.stats.linear_solver.rfind("gmres", 0), 0u) << g.stats.linear_solver;
    expect_same_states(g, d, 1e-5);
    // the exact own block as preconditioner: about one Krylov iteration per Newton iteration
    EXPECT_GT(g.stats.linear_iterations, 0);
    EXPECT_LT(g.stats.linear_iterations, 2 * g.stats.nonlinear_iterations);
  }
}

TEST(LinearSolvers, GmresRefusesSensitivitiesAndUnknownChoicesAreNamed) {
  Scene s = scene_from_file("flowsheets/pbm_constant_kernel.yaml");
  SimOptions o = s.options;
  o.linear_solver = LinearSolverChoice::kGmres;
  o.sensitivities = {"pbm.agg_beta0"};
  EXPECT_THROW(simulate(*s.flowsheet, o), ConfigError);
  o.sensitivities.clear();
  try {
    o.linear_solver = parse_linear_solver("krylov");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("auto, dense, sparse, gmres"), std::string::npos) << e.what();
  }
}

// A matrix whose states fall into independent groups, interleaved in the state order (as two processes side by side
// in one flowsheet are, with their accumulators between them): the dense solver factors each group on its own and
// returns the solution of the whole system, also when x and b are one vector; a singular group fails the setup.
TEST(LinearSolvers, DenseSolverFactorsIndependentGroupsSeparately) {
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  const int n = 9;
  const std::vector<std::vector<int>> groups{{0, 3, 5, 8}, {1, 2, 6}, {4}, {7}};
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SUNMatrix A = SUNDenseMatrix(n, n, ctx);
  Eigen::Map<Eigen::MatrixXd> a(SUNDenseMatrix_Data(A), n, n);
  a.setZero();
  for (const auto& g : groups)
    for (int i : g)
      for (int j : g) a(i, j) = u(rng) + (i == j ? 3.0 : 0.0);
  a(3, 0) = 0.0;  // a structural zero inside a group does not split it
  const Eigen::MatrixXd full = a;
  N_Vector b = N_VNew_Serial(n, ctx), x = N_VNew_Serial(n, ctx);
  Eigen::Map<Eigen::VectorXd> bv(N_VGetArrayPointer(b), n), xv(N_VGetArrayPointer(x), n);
  for (int i = 0; i < n; ++i) bv[i] = u(rng);
  const Eigen::VectorXd want = full.partialPivLu().solve(Eigen::VectorXd(bv));
  SUNLinearSolver s = detail::make_eigen_dense_solver(ctx);
  EXPECT_EQ(detail::eigen_dense_largest_block(s), 0);  // nothing factored yet
  ASSERT_EQ(SUNLinSolSetup(s, A), 0);
  EXPECT_EQ(detail::eigen_dense_groups(s), 4);
  EXPECT_EQ(detail::eigen_dense_largest_block(s), 4);  // what decides how long IDA keeps a factorization
  ASSERT_EQ(SUNLinSolSolve(s, A, x, b, 0.0), 0);
  EXPECT_LT((xv - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff());
  EXPECT_LT((full * xv - bv).cwiseAbs().maxCoeff(), 1e-13);
  ASSERT_EQ(SUNLinSolSolve(s, A, b, b, 0.0), 0);  // in place
  EXPECT_LT((bv - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff());
  // a group that is singular on its own (one state whose equation does not depend on it)
  a(4, 4) = 0.0;
  EXPECT_NE(SUNLinSolSetup(s, A), 0);
  // a coupling that lands between a group's states (row 3 inside the span 1..6 of {1, 2, 6}) joins two groups
  a(4, 4) = 2.0, a(3, 2) = 0.5;
  ASSERT_EQ(SUNLinSolSetup(s, A), 0);
  EXPECT_EQ(detail::eigen_dense_groups(s), 3);
  EXPECT_EQ(detail::eigen_dense_largest_block(s), 7);
  ASSERT_EQ(SUNLinSolSolve(s, A, x, b, 0.0), 0);
  const Eigen::MatrixXd joined = a;
  EXPECT_LT((joined * xv - bv).cwiseAbs().maxCoeff(), 1e-13);
  // coupled groups are one: the whole matrix is factored as before
  a(4, 4) = 2.0, a(0, 1) = 0.5, a(4, 7) = 0.25, a(2, 4) = -0.5;
  ASSERT_EQ(SUNLinSolSetup(s, A), 0);
  EXPECT_EQ(detail::eigen_dense_groups(s), 1);
  EXPECT_EQ(detail::eigen_dense_largest_block(s), n);
  SUNLinSolFree(s);
  SUNMatDestroy(A);
  // a coupled block of 30 states beside one loose state: not worth splitting, factored whole
  const int m = 31;
  A = SUNDenseMatrix(m, m, ctx);
  Eigen::Map<Eigen::MatrixXd> c(SUNDenseMatrix_Data(A), m, m);
  c.setZero();
  c.topLeftCorner(30, 30) = Eigen::MatrixXd::Random(30, 30) + 4.0 * Eigen::MatrixXd::Identity(30, 30);
  c(30, 30) = 1.0;
  s = detail::make_eigen_dense_solver(ctx);
  ASSERT_EQ(SUNLinSolSetup(s, A), 0);
  EXPECT_EQ(detail::eigen_dense_groups(s), 1);
  EXPECT_EQ(detail::eigen_dense_largest_block(s), m);
  SUNLinSolFree(s);
  N_VDestroy(b), N_VDestroy(x);
  SUNMatDestroy(A);
  SUNContext_Free(&ctx);
}

}  // namespace
}  // namespace granuflow
