// The class-local Newton matrix (solver.linear_solver: class_local): the solver factors each size class's block and
// the border exactly and reads nothing between classes but the conservation terms; the fluid bed's Jacobian for it
// keeps its own entries within each class and every row of a state that is not per class, and reports, per conserved
// block and column, the sum of what it left out.
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <random>
#include <regex>

#include "class_local_solver.hpp"
#include "granuflow/dae_system.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

// The solver on its own: 4 classes of 2 states each, interleaved with 3 border states.
struct Fixture {
  static constexpr int n = 11;
  SUNContext ctx = nullptr;
  SUNMatrix A = nullptr;
  N_Vector b = nullptr, x = nullptr;
  detail::ClassStructure st;
  Fixture() {
    SUNContext_Create(nullptr, &ctx);
    A = SUNDenseMatrix(n, n, ctx);
    b = N_VNew_Serial(n, ctx), x = N_VNew_Serial(n, ctx);
    st.cls = {0, 1, -1, 2, 3, 0, 1, -1, 2, 3, -1};  // two units' classes 0..3, three states not per class
    st.group = {0, 0, -1, 0, 0, 1, 1, -1, 1, 1, -1};
    st.groups = 2;
  }
  ~Fixture() {
    N_VDestroy(b), N_VDestroy(x);
    SUNMatDestroy(A);
    SUNContext_Free(&ctx);
  }
  Eigen::Map<Eigen::MatrixXd> a() { return {SUNDenseMatrix_Data(A), n, n}; }
  Eigen::Map<Eigen::VectorXd> bv() { return {N_VGetArrayPointer(b), n}; }
  Eigen::Map<Eigen::VectorXd> xv() { return {N_VGetArrayPointer(x), n}; }
  bool between_classes(int i, int j) const { return st.cls[i] >= 0 && st.cls[j] >= 0 && st.cls[i] != st.cls[j]; }
  // A random matrix with a dominant diagonal into A, and a random right-hand side into b; returns the matrix.
  Eigen::MatrixXd random(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) a()(i, j) = u(rng) + (i == j ? 4.0 : 0.0);
    for (int i = 0; i < n; ++i) bv()[i] = u(rng);
    return a();
  }
};

TEST(ClassLocalSolver, SolvesBlocksAndBorderToRoundOffAndReadsNothingBetweenClasses) {
  Fixture f;
  auto a = f.a();
  Eigen::MatrixXd local = f.random(3);
  for (int j = 0; j < Fixture::n; ++j)
    for (int i = 0; i < Fixture::n; ++i)
      if (f.between_classes(i, j)) local(i, j) = 0.0;
  const Eigen::VectorXd rhs = f.bv();
  SUNLinearSolver ls = detail::make_class_local_solver(f.ctx, {f.st, {}, nullptr});
  ASSERT_EQ(SUNLinSolSetup(ls, f.A), 0);
  ASSERT_EQ(SUNLinSolSolve(ls, f.A, f.x, f.b, 0.0), 0);
  // the solution of the matrix without the entries between classes, not of the whole one
  const Eigen::VectorXd want = local.lu().solve(rhs), whole = Eigen::MatrixXd(a).lu().solve(rhs);
  EXPECT_LT((f.xv() - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff());
  EXPECT_GT((want - whole).cwiseAbs().maxCoeff(), 1e-3);
  // x and b may be one vector (the integrator passes them so)
  ASSERT_EQ(SUNLinSolSolve(ls, f.A, f.b, f.b, 0.0), 0);
  EXPECT_LT((f.bv() - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff());
  // asked for the whole matrix (consistent initial values), it factors every entry
  detail::class_local_whole(ls, true);
  f.bv() = rhs;
  ASSERT_EQ(SUNLinSolSetup(ls, f.A), 0);
  ASSERT_EQ(SUNLinSolSolve(ls, f.A, f.x, f.b, 0.0), 0);
  EXPECT_LT((f.xv() - whole).cwiseAbs().maxCoeff(), 1e-13 * whole.cwiseAbs().maxCoeff());
  const detail::ClassLocalStats s = detail::class_local_stats(ls);
  EXPECT_EQ(s.setups, 2);
  EXPECT_EQ(s.whole_setups, 1);
  EXPECT_EQ(s.classes, 4);
  EXPECT_EQ(s.largest_block, 2);
  EXPECT_EQ(s.border, 3);
  SUNLinSolFree(ls);
}

// The conservation terms: a block's total changes under a correction x as under the exact matrix, 1_g^T A x = 1_g^T b,
// with some entries between classes absent from the matrix the solver gets (the unit left them out and reported
// their column sums over the block) and the others present but not factored.
TEST(ClassLocalSolver, CorrectionsChangeAConservedBlocksTotalAsTheExactMatrixWould) {
  Fixture f;
  auto a = f.a();
  const Eigen::MatrixXd exact = f.random(5);
  const std::vector<std::vector<int>> blocks{{0, 1, 3, 4}, {5, 6, 8, 9}};  // each unit's four classes
  std::vector<std::vector<double>> left(2, std::vector<double>(Fixture::n, 0.0));
  for (int j = 0; j < Fixture::n; ++j)
    for (int i = 0; i < Fixture::n; ++i)
      if (f.between_classes(i, j) && (i + j) % 2 == 0) {  // left out by the unit, reported per block
        a(i, j) = 0.0;
        for (size_t g = 0; g < blocks.size(); ++g)
          for (int r : blocks[g]) left[g][j] += r == i ? exact(i, j) : 0.0;
      }
  const Eigen::VectorXd rhs = f.bv();
  SUNLinearSolver ls =
      detail::make_class_local_solver(f.ctx, {f.st, blocks, [&left](int g) { return left[g].data(); }});
  ASSERT_EQ(SUNLinSolSetup(ls, f.A), 0);
  ASSERT_EQ(SUNLinSolSolve(ls, f.A, f.x, f.b, 0.0), 0);
  const Eigen::VectorXd x = f.xv(), ax = exact * x;
  for (const auto& block : blocks) {
    double moved = 0.0, asked = 0.0;
    for (int r : block) moved += ax[r], asked += rhs[r];
    EXPECT_NEAR(moved, asked, 1e-13 * rhs.cwiseAbs().sum());
  }
  // not the exact solution: only the totals are held to the exact matrix
  EXPECT_GT((x - exact.lu().solve(rhs)).cwiseAbs().maxCoeff(), 1e-3);
  SUNLinSolFree(ls);
}

TEST(ClassLocalSolver, ASingularClassBlockFailsTheSetupRecoverably) {
  Fixture f;
  auto a = f.a();
  a.setIdentity();
  a(3, 3) = 0.0, a(8, 3) = 0.0;  // class 2: its two states' column of state 3 is zero within the class
  a(3, 0) = 5.0;                 // an entry between classes does not rescue it
  SUNLinearSolver ls = detail::make_class_local_solver(f.ctx, {f.st, {}, nullptr});
  EXPECT_EQ(SUNLinSolSetup(ls, f.A), 1);  // positive: the integrator retries with a smaller step
  SUNLinSolFree(ls);
}

// Per state its size class, for every unit with classes (explicit ones too: in the system over all states they are
// unknowns), -1 for the states that are not per class.
std::vector<int> classes_of(const DaeSystem& sys) {
  std::vector<int> cls(sys.size(), -1);
  for (const auto& u : sys.flowsheet().units()) {
    const ClassLayout& layout = u.spec.classes();
    for (StateId b : layout.state_blocks)
      for (int i = 0; i < layout.n; ++i) cls[u.offset + b.i + i] = i;
  }
  return cls;
}

// The headline scene's Jacobian over all states at a state inside the run, exact and as the class-local matrix asks
// for it. Equal on every row of a state not per class, and within every class in the columns of the bed's own states
// (its mass and water: deaths, births that stay in a class, breakage within a class, layering); in every column the
// entries left out sum, over each conserved block (the bed's masses, its water), to what the bed reported left out.
// `skips`: whether the bed left out entries between classes (the pair terms) or formed its whole Jacobian.
void expect_local_jacobian_conserves(const std::string& bed_settings, bool skips) {
  Scene base = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  std::string text = std::regex_replace(base.text, std::regex("classes: 10"), "classes: 14");
  if (!bed_settings.empty())
    text = std::regex_replace(text, std::regex("    type: fluid_bed\n"),
                              "    type: fluid_bed\n    settings: {" + bed_settings + "}\n");
  Scene s = scene_from_text(text);
  SimOptions o = s.options;
  o.t_out = {0, 900};
  const SimResult r = simulate(*s.flowsheet, o);
  DaeSystem sys(*s.flowsheet, false);
  const int n = sys.size();
  ASSERT_EQ(n, r.n_states());
  std::vector<double> y(r.y.begin() + n, r.y.begin() + 2 * n), yp(r.yp.begin() + n, r.yp.begin() + 2 * n);
  std::vector<double> exact(size_t(n) * n), local(size_t(n) * n);
  sys.jacobian(900.0, y.data(), yp.data(), 0.3, exact.data(), nullptr);
  sys.set_classes_local(true);
  sys.jacobian(900.0, y.data(), yp.data(), 0.3, local.data(), nullptr);
  const std::vector<int> cls = classes_of(sys);
  const auto& blocks = sys.conserved_blocks();
  ASSERT_EQ(blocks.size(), 2u);  // the bed's masses and its water
  std::vector<char> bed(n, 0);
  for (const auto& b : blocks)
    for (int k : b) bed[k] = 1;
  double scale = 0.0;
  for (double v : exact) scale = std::max(scale, std::abs(v));
  int left_out = 0;
  for (int c = 0; c < n; ++c) {
    for (int row = 0; row < n; ++row) {
      const double e = exact[size_t(c) * n + row], l = local[size_t(c) * n + row];
      if (cls[row] < 0 || (cls[row] == cls[c] && bed[c]))
        ASSERT_NEAR(l, e, 1e-12 * scale) << "row " << row << " (class " << cls[row] << "), col " << c;
      left_out += l != e;
    }
    for (size_t g = 0; g < blocks.size(); ++g) {
      double missing = 0.0;
      for (int row : blocks[g]) missing += exact[size_t(c) * n + row] - local[size_t(c) * n + row];
      EXPECT_NEAR(missing, sys.left_out(static_cast<int>(g))[c], 1e-11 * scale) << "block " << g << ", col " << c;
    }
  }
  if (skips)
    EXPECT_GT(left_out, n);  // the pair terms between classes were not formed
  else
    EXPECT_EQ(left_out, 0);
}

TEST(ClassLocalJacobian, TheFluidBedKeepsItsOwnEntriesAndReportsWhatItLeftOut) {
  // glass-transition aggregation on the fixed pivot with its fields, Vogel-Peukert breakage, the top class's fold
  expect_local_jacobian_conserves("", true);
}

TEST(ClassLocalJacobian, ASchemeThatCannotSayWhereBirthsStayFormsTheWholeJacobian) {
  expect_local_jacobian_conserves("aggregation_scheme: cell_average, breakage: none", false);
}

TEST(ClassLocalJacobian, AggregatesRemovedAtTheGridsEndFormTheWholeJacobian) {
  // what leaves the grid is lost: the pair terms do not conserve, and what is left out is not minus what is kept
  expect_local_jacobian_conserves("outside: remove", false);
}

}  // namespace
}  // namespace granuflow
