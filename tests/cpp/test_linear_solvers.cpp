// The linear solvers of the Newton iterations: the iterative one (solver.linear_solver: gmres, GMRES on
// difference-quotient Jacobian-vector products with the block preconditioner of DaeSystem) gives the answer of the
// direct ones on flowsheets built for those (units without their own preconditioner get their exact own block), and
// says what it cannot do.
#include <gtest/gtest.h>

#include <cmath>

#include "granuflow/errors.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

// Every state at the last output time, run with `solver` (and the integrator `method`).
SimResult run(Scene& s, const std::string& solver, const std::string& method = "auto") {
  SimOptions o = s.options;
  o.linear_solver = solver;
  o.method = method;
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
  o.linear_solver = "gmres";
  o.sensitivities = {"pbm.agg_beta0"};
  EXPECT_THROW(simulate(*s.flowsheet, o), ConfigError);
  o.sensitivities.clear();
  o.linear_solver = "krylov";
  try {
    simulate(*s.flowsheet, o);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("auto, dense, sparse, gmres"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace granuflow
