// The band + low-rank linear solver (solver.linear_solver: banded) on the Newton matrix of the two-zone layering
// scene: it reads the scene's structure (class-major band, one outer product per spraying unit, the scalar states as
// border), solves to round-off against the dense LU, factors a matrix that is not of that form densely, and gives
// the dense solver's run.
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <fstream>
#include <random>
#include <sstream>

#include "banded_lowrank_solver.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::repo_path;
using testing::scene_from_text;

// The two-zone scene with `classes` classes over `minutes` minutes and the linear solver `solver`.
Scene two_zone(int classes, int minutes, const std::string& solver) {
  std::ifstream f(repo_path("flowsheets/two_zone_layering.yaml"));
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str();
  auto swap = [&](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  swap("classes: 100", "classes: " + std::to_string(classes));
  swap("t_end: 90 min", "t_end: " + std::to_string(minutes) + " min");
  swap("linear_solver: banded}", "linear_solver: " + solver + "}");
  return scene_from_text(text);
}

double residual(const Eigen::MatrixXd& a, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (a * x - b).cwiseAbs().maxCoeff() / (a.cwiseAbs().maxCoeff() * x.cwiseAbs().maxCoeff());
}

TEST(BandedLowRankSolver, SolvesTheTwoZoneNewtonMatrixToRoundOff) {
  Scene s = two_zone(60, 90, "banded");
  DaeSystem sys(*s.flowsheet, true);
  const int n = sys.size();
  std::vector<double> y, yp(n, 0.0);
  sys.initial_values(y);
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  SUNMatrix A = SUNDenseMatrix(n, n, ctx);
  N_Vector b = N_VNew_Serial(n, ctx), x = N_VNew_Serial(n, ctx);
  Eigen::Map<Eigen::MatrixXd> a(SUNDenseMatrix_Data(A), n, n);
  Eigen::Map<Eigen::VectorXd> bv(N_VGetArrayPointer(b), n), xv(N_VGetArrayPointer(x), n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n; ++i) bv[i] = u(rng);
  SUNLinearSolver ls = detail::make_banded_lowrank_solver(ctx, detail::class_structure(sys));
  for (double cj : {1e-2, 1.0, 1e3}) {  // from a nearly singular Jacobian to a nearly diagonal Newton matrix
    SCOPED_TRACE(cj);
    sys.jacobian(0.0, y.data(), yp.data(), cj, a.data(), nullptr);
    const Eigen::MatrixXd full = a;
    ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
    const auto st = detail::banded_lowrank_stats(ls);
    EXPECT_EQ(st.dense_setups, 0);
    EXPECT_EQ(st.rank, 2);  // the spray zone's and the one-zone bed's layering; the drying zone does not grow
    // three zones side by side: two classes below (the limiter's stencil), one above
    EXPECT_LE(st.lower, 3 * 2);
    EXPECT_LE(st.upper, 3 * 1);
    EXPECT_LT(st.worst_outside, 1e-13);
    EXPECT_GT(st.border, 0);
    EXPECT_LE(st.border, 12);
    ASSERT_EQ(SUNLinSolSolve(ls, A, x, b, 0.0), 0);
    EXPECT_LT(residual(full, xv, bv), 1e-13);
    const Eigen::VectorXd want = full.partialPivLu().solve(Eigen::VectorXd(bv));
    EXPECT_LT((xv - want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff());
  }
  // a coupling of distant classes that is no outer product (as aggregation adds): factored whole, still right
  const auto cls = detail::class_structure(sys);
  int lo = -1, hi = -1;
  for (int i = 0; i < n; ++i)
    if (cls.group[i] == 0 && cls.cls[i] == 5)
      lo = i;
    else if (cls.group[i] == 0 && cls.cls[i] == 40)
      hi = i;
  ASSERT_GE(lo, 0);
  ASSERT_GE(hi, 0);
  const Eigen::MatrixXd of_the_form = a;
  a(lo, hi) += 0.5 * a.cwiseAbs().maxCoeff();
  const Eigen::MatrixXd full = a;
  ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 1);
  ASSERT_EQ(SUNLinSolSolve(ls, A, x, b, 0.0), 0);
  EXPECT_LT(residual(full, xv, bv), 1e-13);
  // Not of the form a second time in a row: the next eight setups factor densely without looking, even a matrix of
  // the form; the one after looks again and finds it.
  ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 2);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).untested_setups, 0);
  a = of_the_form;
  for (int k = 1; k <= 8; ++k) {
    ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
    EXPECT_EQ(detail::banded_lowrank_stats(ls).untested_setups, k);
    EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 2 + k);
    ASSERT_EQ(SUNLinSolSolve(ls, A, x, b, 0.0), 0);
    EXPECT_LT(residual(of_the_form, xv, bv), 1e-13);
  }
  ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 10);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).untested_setups, 8);
  ASSERT_EQ(SUNLinSolSolve(ls, A, x, b, 0.0), 0);
  EXPECT_LT(residual(of_the_form, xv, bv), 1e-13);
  // Two misses again, then a new segment of the run (where a restarted run starts with a new solver): it looks again.
  a = full;
  for (int k = 0; k < 2; ++k) ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 12);
  detail::banded_lowrank_new_segment(ls);
  a = of_the_form;
  ASSERT_EQ(SUNLinSolSetup(ls, A), 0);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).dense_setups, 12);
  EXPECT_EQ(detail::banded_lowrank_stats(ls).untested_setups, 8);
  SUNLinSolFree(ls);
  N_VDestroy(b), N_VDestroy(x);
  SUNMatDestroy(A);
  SUNContext_Free(&ctx);
}

// The whole run: the sizes of the dense solver's run within the integrator's tolerance.
TEST(BandedLowRankSolver, GivesTheDenseRun) {
  Scene banded = two_zone(40, 20, "banded"), dense = two_zone(40, 20, "dense");
  const SimResult rb = simulate(*banded.flowsheet, banded.options), rd = simulate(*dense.flowsheet, dense.options);
  EXPECT_EQ(rb.stats.linear_solver.rfind("banded", 0), 0u) << rb.stats.linear_solver;
  // Every setup factored as band + outer products + border: a setup that fell back to the dense LU is named there.
  // (Whether an output also differs from the dense run in its last bits depends on the CPU: on one with AVX-512,
  // two of these four come out equal to the bit.)
  EXPECT_EQ(rb.stats.linear_solver.find("dense LU"), std::string::npos) << rb.stats.linear_solver;
  for (const char* key : {"drying.sigma", "drying.d_mean", "onezone.sigma", "spray.sigma"}) {
    const double b = testing::output(rb, rb.t.size() - 1, key), d = testing::output(rd, rd.t.size() - 1, key);
    EXPECT_NEAR(b, d, 1e-6 * std::abs(d)) << key;
  }
}

}  // namespace
}  // namespace granuflow
