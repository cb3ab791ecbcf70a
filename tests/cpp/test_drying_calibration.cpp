// The gamma drying curve's parameter (paper 000, section 5.4.1) in calibration: the sensitivity of the bed moisture
// to bed.drying_gamma equals finite differences of simulations, and one stage recovers gamma from noise-free data
// made with a known gamma (flowsheets/paper000_drying_closures.yaml, its drying phase).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "granuflow/calibration.hpp"
#include "granuflow/output_sensitivity.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::output_index;

// The comparison scene with the gamma curve (the scene names its closures in one settings line).
Scene gamma_scene() {
  std::ifstream f(testing::repo_path("flowsheets/paper000_drying_closures.yaml"));
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str();
  const std::string from = "{drying_curve: linear,", to = "{drying_curve: gamma,";
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, from.size(), to);
  return testing::scene_from_text(text);
}

const std::vector<double> kTimes = {900, 1200, 1500, 1800, 2100, 2400};  // s, the drying phase after the spray

TEST(DryingCalibration, MoistureSensitivityToGammaEqualsFiniteDifferences) {
  Scene s = gamma_scene();
  s.flowsheet->set_param("bed.drying_gamma", 2.0);
  SimOptions o = s.options;
  o.t_out = {0, 1200, 1800};
  o.rtol = 1e-9;
  o.atol = 1e-11;
  o.sensitivities = {"bed.drying_gamma"};
  const SimResult r = simulate(*s.flowsheet, o);
  const auto dz = output_sensitivities(*s.flowsheet, r);
  const size_t no = r.output_names.size();
  const int j = output_index(r, "bed.moisture");
  auto run = [&](double g) {
    Scene q = gamma_scene();
    q.flowsheet->set_param("bed.drying_gamma", g);
    SimOptions oo = o;
    oo.sensitivities.clear();
    oo.rtol = 1e-10;
    oo.atol = 1e-12;
    return simulate(*q.flowsheet, oo);
  };
  const double h = 1e-3;
  const SimResult a = run(2.0 + h), b = run(2.0 - h);
  for (int k : {1, 2}) {
    const double fd = (a.outputs[k * no + j] - b.outputs[k * no + j]) / (2 * h);
    EXPECT_LT(fd, 0.0) << "a larger gamma dries faster";
    EXPECT_NEAR(dz[k * no + j], fd, 2e-3 * std::abs(fd)) << "t = " << o.t_out[k];
  }
}

TEST(DryingCalibration, OneStageRecoversGamma) {
  Scene s = gamma_scene();
  const double truth = 2.5;
  Experiment e;
  e.name = "wet_batch";
  e.t_end = kTimes.back();
  Observation ob;
  ob.name = "bed.moisture";
  ob.t = kTimes;
  ob.value.assign(kTimes.size(), 1.0);
  // The plant's drying is limited by what the gas can carry (docs/drying_closures.md): gamma moves the moisture by
  // about 1e-4 kg/kg, so a measurement must resolve that to see it.
  ob.sigma_abs = 1e-6;
  e.observations = {ob};
  std::vector<Experiment> exps{e};
  CalibrationOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  const auto pred = predict(s, units::builtin(), exps, {{"bed.drying_gamma", truth}}, o);
  ASSERT_EQ(pred.size(), 1u);
  exps[0].observations[0].value = pred[0].model;
  Stage st;
  st.name = "drying_curve";
  st.free = {{"bed.drying_gamma", Transform::kLog, 0.1, 50.0, {}}};
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.function_tolerance = 1e-12;
  o.parameter_tolerance = 1e-10;
  o.cost_change_tolerance = 0;
  const CalibrationResult r = calibrate(s, units::builtin(), exps, {st}, o, {{"bed.drying_gamma", 1.2}});
  ASSERT_EQ(r.stages.size(), 1u);
  EXPECT_EQ(r.stages[0].termination, "CONVERGENCE") << r.stages[0].message;
  EXPECT_NEAR(r.parameters.at("bed.drying_gamma"), truth, 1e-3 * truth);
  EXPECT_TRUE(r.stages[0].estimates[0].identifiable) << r.stages[0].estimates[0].flag;
}

}  // namespace
}  // namespace granuflow
