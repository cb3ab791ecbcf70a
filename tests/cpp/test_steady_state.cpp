// Steady states: conserved hold-ups kept, the answer of a long dynamic run, pseudo-transient continuation when
// Newton alone fails, the trivial root named, and a clear error when there is no steady state.
#include <gtest/gtest.h>

#include "granuflow/errors.hpp"
#include "pbm_test_helpers.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;

TEST(SteadyState, BatchBedKeepsItsHoldUpAndEqualsALongRun) {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  const SteadyResult ss = solve_steady_state(*s.flowsheet, SteadyOptions{});
  ASSERT_EQ(ss.conserved.size(), 1u);  // the bed's solids: aggregation and breakage keep mass
  EXPECT_NE(ss.conserved[0].find("bed (M_0 .. M_9)"), std::string::npos) << ss.conserved[0];
  EXPECT_TRUE(ss.warnings.empty());
  const Flowsheet& fs = *s.flowsheet;
  std::vector<double> y0;
  double m0 = 0, m = 0;
  for (int i = 0; i < 10; ++i) m += ss.y[fs.state_id("bed.M_" + std::to_string(i))];
  {
    DaeSystem sys(fs);
    sys.initial_values(y0);
    for (int i = 0; i < 10; ++i) m0 += y0[fs.state_id("bed.M_" + std::to_string(i))];
  }
  EXPECT_NEAR(m, m0, 1e-12 * m0);
  // spraying for 20 h: the dynamic run ends where the steady-state solve lands
  s.flowsheet->set_param("nozzle.t_off", 20 * 3600.0);
  SimOptions o = s.options;
  o.t_end = 20 * 3600.0;
  o.t_out = {0, o.t_end};
  o.rtol = 1e-9, o.atol = 1e-9;
  const SimResult r = simulate(*s.flowsheet, o);
  for (const std::string name : {"bed.M_0", "bed.M_5", "bed.M_9", "bed.W_3", "bed.T", "gas.T", "gas.Y"}) {
    const int i = fs.state_id(name);
    EXPECT_NEAR(ss.y[i], r.state(1, i), 1e-7 * std::abs(r.state(1, i))) << name;
  }
}

TEST(SteadyState, PseudoTransientContinuationWhenNewtonAloneFails) {
  // a continuous dryer started at 4 kg of a finer, drier bed: its hold-up relaxes over 1000 s, the gas in seconds
  Scene s = scene_from_file("flowsheets/continuous_drying_bed.yaml");
  SteadyOptions o;
  const SteadyResult ss = solve_steady_state(*s.flowsheet, o);
  EXPECT_EQ(ss.method, "pseudo-transient continuation, then newton");
  // steps grow geometrically while the residual falls: tens of steps, not thousands, across six decades of time
  EXPECT_GT(ss.pseudo_steps, 0);
  EXPECT_LT(ss.pseudo_steps, 60);
  o.max_pseudo_steps = 0;  // Newton from the initial state alone does not converge
  EXPECT_THROW(solve_steady_state(*s.flowsheet, o), SolverError);
  // the answer is the end of a long run
  SimOptions so = s.options;
  so.t_end = 40 * 3600.0, so.t_out = {0, so.t_end}, so.rtol = so.atol = 1e-10;
  const SimResult r = simulate(*s.flowsheet, so);
  const Flowsheet& fs = *s.flowsheet;
  // bed.M_0 holds about 6e-13 kg: below 1e-12 of the 4-kg hold-up the two answers need only agree absolutely (a build
  // with FMA gave 3.6e-4 relative there, 2e-16 kg)
  const double floor_kg = 1e-12 * 4.0;
  for (const std::string name : {"bed.M_0", "bed.M_6", "bed.W_6", "bed.T", "gas.T", "gas.Y"}) {
    const int i = fs.state_id(name);
    const double abs_floor = name.rfind("bed.M_", 0) == 0 || name.rfind("bed.W_", 0) == 0 ? floor_kg : 0.0;
    EXPECT_NEAR(ss.y[i], r.state(1, i), 1e-7 * std::abs(r.state(1, i)) + abs_floor) << name;
  }
}

TEST(SteadyState, NewtonAloneForTheBatchBedOnceRowsAreWeighted) {
  // the enthalpy identity H - C (T - T0) (about 1e6 J) and the solids balances (1e-3 kg/s) are weighted by their
  // own size: Newton converges from the start, and holds every row to the same relative tolerance
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  const SteadyResult ss = solve_steady_state(*s.flowsheet, SteadyOptions{});
  EXPECT_EQ(ss.method, "newton");
  EXPECT_LT(ss.iterations, 30);
}

TEST(SteadyState, AggregationThatEmptiesTheGridFindsAndNamesTheTrivialRoot) {
  // aggregates beyond the top edge leave (outside = remove): the population empties
  auto fs = pbm_test::flowsheet(
      {{"q", "1"}, {"classes", "12"}, {"aggregation", "constant"}, {"aggregation_scheme", "fixed_pivot"}},
      {{"agg_beta0", 1.0}});
  const SteadyResult ss = solve_steady_state(*fs, SteadyOptions{});
  ASSERT_EQ(ss.warnings.size(), 1u);
  EXPECT_NE(ss.warnings[0].find("trivial"), std::string::npos);
  EXPECT_NE(ss.warnings[0].find("'pbm'"), std::string::npos);
}

TEST(SteadyState, AggregationAndBreakageReachAnEquilibriumAtTheInitialMass) {
  auto fs = pbm_test::flowsheet({{"q", "2"},
                                 {"classes", "30"},
                                 {"aggregation", "constant"},
                                 {"aggregation_scheme", "fixed_pivot"},
                                 {"breakage", "linear"},
                                 {"outside", "fold"}},
                                {{"agg_beta0", 1.0}, {"sel_s0", 1.0}});
  const SteadyResult ss = solve_steady_state(*fs, SteadyOptions{});
  EXPECT_TRUE(ss.warnings.empty());
  ASSERT_FALSE(ss.conserved.empty());
  const auto g = pbm_test::grid(2, 15);
  double v = 0, v0 = 0;
  std::vector<double> y0;
  DaeSystem sys(*fs);
  sys.initial_values(y0);
  for (int i = 0; i < g.size(); ++i) v += ss.y[i] * g.pivot(i), v0 += y0[i] * g.pivot(i);
  EXPECT_NEAR(v, v0, 1e-10 * v0);  // the volume (mass) the batch started with
  std::vector<double> r(sys.size()), zeros(sys.size(), 0.0);
  sys.residual(0.0, ss.y.data(), zeros.data(), r.data());
  for (int i = 0; i < g.size(); ++i) EXPECT_NEAR(r[i], 0.0, 1e-9) << i;  // dN/dt = 0: an equilibrium
}

TEST(SteadyState, AHeatedTankWithoutFlowHasNoneAndSaysWhy) {
  Scene s = testing::scene_from_text(R"(
scene: heated_tank_without_flow
t_end: 1 h
units:
  feed: {type: liquid_feed, params: {mdot: 0 kg/s}}
  tank: {type: stirred_tank, params: {mass: 100 kg, Q: 10 kW}}
  product: {type: liquid_product}
connections: [feed.out -> tank.in, tank.out -> product.in]
)");
  try {
    solve_steady_state(*s.flowsheet, SteadyOptions{});
    FAIL() << "a heated tank without flow has no steady state";
  } catch (const SolverError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("has no steady state"), std::string::npos) << m;
    EXPECT_NE(m.find("tank (T)"), std::string::npos) << m;
    EXPECT_NE(m.find("constant rate"), std::string::npos) << m;
    EXPECT_EQ(e.unit(), "tank");
  }
}

}  // namespace
}  // namespace granuflow
