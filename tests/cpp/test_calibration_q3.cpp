// Measured size distributions as calibration data (framework/calibration/src/size_fraction.hpp): the observable
// unit.Q3(size) is the model's cumulative mass fraction below the size (exactly the initial log-normal's at a class
// edge), its residual Jacobian equals finite differences, and malformed observables or data are refused.
#include <gtest/gtest.h>

#include <cmath>

#include "granuflow/calibration.hpp"
#include "granuflow/errors.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;

Scene short_headline() {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  s.options.t_end = 1200.0;
  return s;
}

Experiment q3_experiment(const std::vector<std::string>& names, std::vector<double> t) {
  Experiment e;
  e.name = "q3";
  e.t_end = t.back();
  for (const auto& n : names) {
    Observation o;
    o.name = n;
    o.t = t;
    o.value.assign(t.size(), 0.5);
    o.sigma_abs = 0.01;
    e.observations.push_back(o);
  }
  return e;
}

TEST(CalibrationQ3, AtAClassEdgeTheInitialQ3IsTheLognormalsCumulative) {
  Scene s = short_headline();
  std::vector<double> d;
  for (const auto& u : s.flowsheet->units())
    if (u.name == "bed") d = u.spec.size_edges();
  ASSERT_EQ(d.size(), 11u);
  const double e3 = d[3], e7 = d[7];
  char n3[64], n7[64], mid[64];
  std::snprintf(n3, sizeof n3, "bed.Q3(%.17g m)", e3);
  std::snprintf(n7, sizeof n7, "bed.Q3(%.17g m)", e7);
  std::snprintf(mid, sizeof mid, "bed.Q3(%.17g m)", std::sqrt(d[5] * d[6]));
  EXPECT_EQ(observable_unit(*s.flowsheet, n3), "-");
  CalibrationOptions o;
  const auto pred = predict(s, units::builtin(), {q3_experiment({n3, n7, mid}, {0.0, 600.0})}, {}, o);
  ASSERT_EQ(pred.size(), 3u);
  auto lognormal = [](double x) { return 0.5 * std::erfc(-std::log(x / 200e-6) / (std::log(1.5) * std::sqrt(2.0))); };
  EXPECT_NEAR(pred[0].model[0], lognormal(e3), 1e-14);
  EXPECT_NEAR(pred[1].model[0], lognormal(e7), 1e-14);
  // half-way in ln d through class 5: half of its mass
  EXPECT_NEAR(pred[2].model[0], 0.5 * (lognormal(d[5]) + lognormal(d[6])), 1e-14);
  EXPECT_LT(pred[1].model[1], pred[1].model[0]);  // aggregation: less mass below a size later
}

TEST(CalibrationQ3, JacobianEqualsFiniteDifferencesOfTheResiduals) {
  Scene s = short_headline();
  std::vector<Experiment> exps{q3_experiment({"bed.Q3(150 um)", "bed.Q3(300 um)", "bed.Q3(600 um)"}, {600, 1200})};
  Stage st;
  st.name = "q3";
  st.free = {{"bed.agg_ln_beta0", Transform::kNone, -25.0, -10.0, {}},
             {"spray_zone.h_pen", Transform::kLog, 1e-5, 5e-3, {}}};
  CalibrationOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.sens_error_control = true;
  StageProblem sp(s, units::builtin(), exps, st, o, {{"bed.agg_ln_beta0", -17.0}});
  ASSERT_EQ(sp.num_residuals(), 6);
  const auto th = sp.theta0();
  std::vector<double> r, J, rp, rm;
  sp.evaluate(th, r, &J);
  for (int k = 0; k < 2; ++k) {
    const double h = 1e-4;
    auto a = th, b = th;
    a[k] += h, b[k] -= h;
    sp.evaluate(a, rp, nullptr);
    sp.evaluate(b, rm, nullptr);
    double colmax = 0;
    for (int i = 0; i < 6; ++i) colmax = std::max(colmax, std::abs(J[size_t(i) * 2 + k]));
    EXPECT_GT(colmax, 0.0);
    for (int i = 0; i < 6; ++i)
      EXPECT_NEAR(J[size_t(i) * 2 + k], (rp[i] - rm[i]) / (2 * h), 1e-4 * colmax) << "row " << i << ", param " << k;
  }
}

void expect_refused(const Flowsheet& fs, const std::vector<Experiment>& exps, const std::string& part) {
  try {
    check_experiments(fs, exps);
    ADD_FAILURE() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(CalibrationQ3, MalformedObservablesAndDataAreRefused) {
  Scene s = short_headline();
  const Flowsheet& fs = *s.flowsheet;
  expect_refused(fs, {q3_experiment({"gas.Q3(300 um)"}, {600})}, "unit 'gas' reports no size distribution");
  expect_refused(fs, {q3_experiment({"bed.Q3(abc)"}, {600})}, "is not a length");
  expect_refused(fs, {q3_experiment({"bed.Q3(300 K)"}, {600})}, "bed.Q3(300 K)");
  expect_refused(fs, {q3_experiment({"nobed.Q3(300 um)"}, {600})}, "no unit 'nobed'");
  auto e = q3_experiment({"bed.Q3(300 um)"}, {600});
  e.observations[0].value[0] = 45.0;  // percent
  expect_refused(fs, {e}, "0 <= Q3 <= 1");
}

}  // namespace
}  // namespace granuflow
