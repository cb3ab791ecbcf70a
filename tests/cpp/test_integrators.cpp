// The integrator chosen per flowsheet (solver.method): what auto picks and why, the same answer from every method
// on an ODE, sensitivities from CVODES, clear refusals, and per-class tolerances that keep explicit methods honest.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "granuflow/errors.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

// Two stirred tanks in series, the first with a residence time of 0.1 s, the second of 200 s, run for 1000 s.
const char* kStiffTanks = R"(
scene: stiff_tanks
t_end: 1000 s
output: {times: [0 s, 10 s, 1000 s]}
solver: {rtol: 1e-8, atol: 1e-10}
units:
  feed: {type: liquid_feed, params: {mdot: 0.5, T: 60 degC, w: 0.2}}
  t0: {type: stirred_tank, params: {mass: 0.05, T0: 20 degC, w0: 0.0}}
  t1: {type: stirred_tank, params: {mass: 100, T0: 20 degC, w0: 0.0}}
  product: {type: liquid_product}
connections: [feed.out -> t0.in, t0.out -> t1.in, t1.out -> product.in]
)";

SimResult run(Scene& s, const std::string& method, std::vector<std::string> sens = {}) {
  SimOptions o = s.options;
  o.method = parse_method(method);
  o.sensitivities = std::move(sens);
  return simulate(*s.flowsheet, o);
}

// Every integrator fails the same way through the one run driver: a SolverError at the time it stopped, naming the
// unit of the worst weighted residual (here a stirred tank: the feed and product hold no states) and its size.
TEST(Integrators, EveryIntegratorsFailureNamesTimeUnitAndWorstResidual) {
  for (const std::string m : {"ida", "bdf", "adams", "erk"}) {
    Scene s = scene_from_text(kStiffTanks);
    SimOptions o = s.options;
    o.method = parse_method(m);
    o.max_steps = 4;  // far too few for 1000 s
    try {
      simulate(*s.flowsheet, o);
      FAIL() << m << " ran 1000 s in 4 steps";
    } catch (const SolverError& e) {
      const std::string msg = e.what();
      EXPECT_GT(e.t(), 0.0) << m << ": " << msg;
      EXPECT_LT(e.t(), 1000.0) << m << ": " << msg;
      EXPECT_TRUE(e.unit() == "t0" || e.unit() == "t1") << m << ": unit '" << e.unit() << "': " << msg;
      EXPECT_TRUE(std::isfinite(e.worst_residual()) && e.worst_residual() >= 0.0) << m << ": " << msg;
      EXPECT_NE(msg.find("unit '" + e.unit() + "'"), std::string::npos) << m << ": " << msg;
      EXPECT_NE(msg.find("worst weighted residual"), std::string::npos) << m << ": " << msg;
      EXPECT_NE(msg.find("TOO_MUCH_WORK"), std::string::npos) << m << ": " << msg;
    }
  }
}

TEST(Integrators, AutoPicksIdasForADaeAndSaysWhy) {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  SimOptions o = s.options;
  o.t_end = 60, o.t_out = {0, 60};
  const SimResult r = simulate(*s.flowsheet, o);
  EXPECT_EQ(r.stats.method, "bdf (IDAS)");
  EXPECT_NE(r.stats.method_reason.find("a DAE"), std::string::npos) << r.stats.method_reason;
  for (const std::string m : {"adams", "erk"}) {
    o.method = parse_method(m);
    try {
      simulate(*s.flowsheet, o);
      FAIL() << m << " ran on a DAE";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("algebraic states"), std::string::npos) << e.what();
    }
  }
}

TEST(Integrators, AutoPicksAnExplicitMethodForANonStiffOdeAndBdfForAStiffOne) {
  Scene easy = scene_from_file("flowsheets/pbm_constant_kernel.yaml");
  const SimResult r = run(easy, "auto");
  EXPECT_EQ(r.stats.method.rfind("erk", 0), 0u) << r.stats.method;
  EXPECT_NE(r.stats.method_reason.find("non-stiff"), std::string::npos) << r.stats.method_reason;
  Scene stiff = scene_from_text(kStiffTanks);
  const SimResult b = run(stiff, "auto");
  EXPECT_EQ(b.stats.method.rfind("bdf (CVODES", 0), 0u) << b.stats.method;
  EXPECT_NE(b.stats.method_reason.find("(stiff)"), std::string::npos) << b.stats.method_reason;
  // the 0.1 s tank limits an explicit method to steps of about 0.3 s: thousands of steps where BDF needs tens
  const SimResult e = run(stiff, "erk");
  EXPECT_GT(e.stats.steps, 10 * b.stats.steps);
}

TEST(Integrators, EveryMethodGivesTheSameAnswerOnAnOde) {
  Scene s = scene_from_text(kStiffTanks);
  const SimResult ref = run(s, "ida");
  const int n = ref.n_states();
  const int w1 = s.flowsheet->state_id("t1.w"), T1 = s.flowsheet->state_id("t1.T");
  // the exact composition of the second tank: two first-order lags in series
  const double tau0 = 0.05 / 0.5, tau1 = 100 / 0.5, t = 1000.0;
  const double w_exact = 0.2 * (1 - (tau1 * std::exp(-t / tau1) - tau0 * std::exp(-t / tau0)) / (tau1 - tau0));
  EXPECT_NEAR(ref.state(2, w1), w_exact, 1e-7);
  for (const std::string m : {"bdf", "adams", "erk"}) {
    SCOPED_TRACE(m);
    const SimResult r = run(s, m);
    EXPECT_NEAR(r.state(2, w1), w_exact, 1e-7);
    EXPECT_NEAR(r.state(2, T1), ref.state(2, T1), 1e-5);
    // quadratures (what the product collected) integrate along
    for (size_t k = 0; k < r.output_names.size(); ++k)
      EXPECT_NEAR(r.outputs[2 * r.output_names.size() + k], ref.outputs[2 * ref.output_names.size() + k],
                  1e-6 * (1 + std::abs(ref.outputs[2 * ref.output_names.size() + k])))
          << r.output_names[k];
  }
  (void)n;
}

TEST(Integrators, CvodesSensitivitiesEqualIdasOnes) {
  // BDF on the stiff tanks, Adams on the (non-stiff) constant-kernel population
  Scene tanks = scene_from_text(kStiffTanks), pbm = scene_from_file("flowsheets/pbm_constant_kernel.yaml");
  const std::pair<Scene*, std::string> cases[] = {{&tanks, "bdf"}, {&pbm, "adams"}};
  const std::vector<std::string> params[] = {{"feed.w", "t1.mass"}, {"pbm.agg_beta0", "pbm.v0"}};
  for (int c = 0; c < 2; ++c) {
    SCOPED_TRACE(cases[c].second);
    Scene& s = *cases[c].first;
    const SimResult ref = run(s, "ida", params[c]);
    const SimResult r = run(s, cases[c].second, params[c]);
    EXPECT_EQ(r.stats.method.rfind(cases[c].second, 0), 0u);
    ASSERT_EQ(r.sens.size(), ref.sens.size());
    double big = 0;
    for (double v : ref.sens) big = std::max(big, std::abs(v));
    for (size_t i = 0; i < r.sens.size(); ++i) EXPECT_NEAR(r.sens[i], ref.sens[i], 1e-5 * big) << i;
    ASSERT_EQ(r.output_sens.size(), ref.output_sens.size());
  }
  try {
    run(tanks, "erk", {"feed.w"});
    FAIL() << "erk returned no sensitivities silently";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("no sensitivities"), std::string::npos) << e.what();
  }
}

TEST(Integrators, VolumeWeightedTolerancesKeepAnExplicitMethodsSecondMomentRight) {
  // Sum kernel to T = 3 on a grid 40 doublings wide, cell average, Dormand-Prince at rtol = atol = 1e-3 (N0 = 1).
  // With one number tolerance for every class, the few particles in classes up to 2^28 times the start volume
  // escape the error test and M2 comes out wrong by orders of magnitude, with no error flag; weighted by the class
  // volume, M2 is as good as the discretization.
  auto g = pbm_test::grid(2, 40);
  auto m2_error = [&](const std::string& weighting, long* steps) {
    auto st = pbm_test::grid_settings(2, 40);
    st["aggregation"] = "sum", st["aggregation_scheme"] = "cell_average", st["tolerance_weighting"] = weighting;
    auto fs = pbm_test::flowsheet(st, {});
    SimOptions o;
    o.t_end = 3, o.t_out = {0, 3}, o.rtol = 1e-3, o.atol = 1e-3, o.method = Method::kErk;
    const SimResult r = simulate(*fs, o);
    *steps = r.stats.steps;
    return pbm_test::moment(g, &r.y[r.n_states()], 2) / pbm_analytic::golovin_m2(3.0) - 1.0;
  };
  long su = 0, sv = 0;
  const double uniform = m2_error("uniform", &su), weighted = m2_error("volume", &sv);
  EXPECT_GT(std::abs(uniform), 100.0);
  EXPECT_LT(std::abs(weighted), 0.15);  // the q = 2 grid's own error is about 0.1
  EXPECT_LT(sv, 4 * su);
}

}  // namespace
}  // namespace granuflow
