// Calibration (Ceres) on the headline scene, shortened to 20 min: output sensitivities and the residual
// Jacobian against finite differences, exact recovery from noise-free data (sensitivities and central
// differences), a parameter the data cannot see flagged, and option validation.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "granuflow/calibration.hpp"
#include "granuflow/interrupt.hpp"
#include "granuflow/output_sensitivity.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::output_index;
using testing::scene_from_file;

Scene short_headline() {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  s.options.t_end = 1200.0;
  return s;
}

// Two operating points (Table 1 corners), observed every 5 min for 20 min; values filled by predict().
std::vector<Experiment> experiments(const std::vector<std::string>& observables) {
  std::vector<Experiment> v;
  const double pts[2][3] = {{600 / 3600.0, 313.15, 1e-3}, {800 / 3600.0, 353.15, 2e-3}};
  for (int k = 0; k < 2; ++k) {
    Experiment e;
    e.name = "run" + std::to_string(k);
    e.settings = {{"inlet.V_dot", pts[k][0]}, {"inlet.T", pts[k][1]}, {"nozzle.mdot", pts[k][2]}};
    e.t_end = 1200.0;
    for (const auto& o : observables) {
      Observation ob;
      ob.name = o;
      ob.t = {300, 600, 900, 1200};
      ob.value.assign(4, 1.0);
      if (o == "gas.T")
        ob.sigma_abs = 2.0;
      else if (o == "bed.moisture")
        ob.sigma_abs = 0.01;
      else
        ob.sigma_rel = 0.07;
      e.observations.push_back(ob);
    }
    v.push_back(e);
  }
  return v;
}

// Data = model at `params` (times `factor`).
void fill_with_model(const Scene& s, std::vector<Experiment>& exps, const std::map<std::string, double>& params,
                     double factor = 1.0) {
  CalibrationOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  const auto pred = predict(s, units::builtin(), exps, params, o);
  for (auto& e : exps)
    for (auto& ob : e.observations)
      for (const auto& p : pred)
        if (p.experiment == e.name && p.observable == ob.name)
          for (size_t i = 0; i < ob.value.size(); ++i) ob.value[i] = p.model[i] * factor;
}

TEST(OutputSensitivities, EqualFiniteDifferencesOfSimulations) {
  const std::vector<std::string> params{"bed.agg_ln_beta0", "droplets.k_evap"};
  Scene s = short_headline();
  SimOptions o = s.options;
  o.t_out = {0, 600, 1200};
  o.rtol = 1e-9;
  o.atol = 1e-11;
  o.sensitivities = params;
  const SimResult r = simulate(*s.flowsheet, o);
  const auto dz = output_sensitivities(*s.flowsheet, r);
  const size_t no = r.output_names.size();
  for (const std::string out : {"bed.d50", "bed.d90", "bed.d16", "bed.moisture"}) {
    const int j = output_index(r, out);
    for (size_t k = 0; k < params.size(); ++k) {
      const double p = s.flowsheet->param(params[k]);
      const double h = params[k] == "bed.agg_ln_beta0" ? 1e-3 : 1e-3 * p;  // small: no class edge in between
      auto run = [&](double v) {
        Scene q = short_headline();
        q.flowsheet->set_param(params[k], v);
        SimOptions oo = o;
        oo.sensitivities.clear();
        oo.rtol = 1e-10;
        oo.atol = 1e-12;
        return simulate(*q.flowsheet, oo).outputs[2 * no + j];
      };
      const double fd = (run(p + h) - run(p - h)) / (2 * h);
      const double an = dz[(2 * params.size() + k) * no + j];
      // d-values are piecewise smooth (kinks where a quantile crosses a class edge): a wide step would
      // straddle one and see the mean of two slopes
      EXPECT_NEAR(an, fd, 2e-3 * std::abs(fd) + 1e-12) << out << " / " << params[k];
    }
  }
}

TEST(StageProblem, JacobianEqualsFiniteDifferencesOfTheResiduals) {
  Scene s = short_headline();
  auto exps = experiments({"gas.T", "bed.moisture", "bed.d50", "bed.d90"});
  fill_with_model(s, exps, {}, 1.03);
  Stage st;
  st.name = "mixed";
  st.free = {{"wall.k_wall", Transform::kLog, 1.0, 200.0, {}},
             {"bed.agg_ln_beta0", Transform::kNone, -25.0, -10.0, {}},
             {"spray_zone.h_pen", Transform::kLog, 1e-5, 5e-3, {}}};
  CalibrationOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.sens_error_control = true;
  StageProblem sp(s, units::builtin(), exps, st, o, {{"wall.k_wall", 18.0}, {"bed.agg_ln_beta0", -17.0}});
  ASSERT_EQ(sp.num_parameters(), 3);
  ASSERT_EQ(sp.num_residuals(), 2 * 4 * 4);
  const auto th = sp.theta0();
  EXPECT_NEAR(th[0], std::log(18.0), 1e-12);
  std::vector<double> r, J, rp, rm;
  sp.evaluate(th, r, &J);  // fixes the weights (σ_rel at this model)
  const int nr = sp.num_residuals();
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-4;
    auto a = th, b = th;
    a[k] += h, b[k] -= h;
    sp.evaluate(a, rp, nullptr);
    sp.evaluate(b, rm, nullptr);
    double colmax = 0;
    for (int i = 0; i < nr; ++i) colmax = std::max(colmax, std::abs(J[size_t(i) * 3 + k]));
    for (int i = 0; i < nr; ++i) {
      const double fd = (rp[i] - rm[i]) / (2 * h);
      EXPECT_NEAR(J[size_t(i) * 3 + k], fd, 1e-4 * colmax) << "row " << i << ", parameter " << k;
    }
  }
  EXPECT_EQ(sp.sensitivity_solves(), 1 * 2);
  // Back at the point of the last Jacobian (where a reweighting pass starts): the residuals of that solve, no new
  // simulation (a plain one would differ from the sensitivity solve's in the last digits)
  const long sims = sp.simulations();
  std::vector<double> again;
  sp.evaluate(th, again, nullptr);
  EXPECT_EQ(sp.simulations(), sims);
  EXPECT_EQ(again, r);
}

Stage two_parameter_stage() {
  Stage st;
  st.name = "wall_and_agglomeration";
  st.free = {{"wall.k_wall", Transform::kLog, 1.0, 200.0, {}},
             {"bed.agg_ln_beta0", Transform::kNone, -25.0, -10.0, {}}};
  return st;
}

TEST(Calibrate, RecoversTheParametersOfNoiseFreeDataExactly) {
  Scene s = short_headline();
  const double k_wall = s.flowsheet->param("wall.k_wall"), ln_beta0 = s.flowsheet->param("bed.agg_ln_beta0");
  auto exps = experiments({"gas.T", "bed.d50", "bed.d90"});
  fill_with_model(s, exps, {});
  CalibrationOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.num_threads = 2;
  o.function_tolerance = 1e-12;
  o.parameter_tolerance = 1e-10;
  o.cost_change_tolerance = 0;
  for (auto method : {JacobianMethod::kSensitivities, JacobianMethod::kCentralDifferences}) {
    o.jacobian = method;
    const CalibrationResult r = calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o,
                                          {{"wall.k_wall", 20.0}, {"bed.agg_ln_beta0", -16.8}});
    ASSERT_EQ(r.stages.size(), 1u);
    const StageResult& st = r.stages[0];
    EXPECT_EQ(st.jacobian_method, to_string(method));
    EXPECT_EQ(st.termination, "CONVERGENCE") << st.message;
    EXPECT_LT(st.cost, 1e-6);
    EXPECT_NEAR(r.parameters.at("wall.k_wall"), k_wall, 1e-4 * k_wall);
    EXPECT_NEAR(r.parameters.at("bed.agg_ln_beta0"), ln_beta0, 1e-4);
    if (method == JacobianMethod::kCentralDifferences)
      EXPECT_EQ(r.sensitivity_solves, 0);
    else
      EXPECT_GT(r.sensitivity_solves, 0);
    for (const auto& e : st.estimates) EXPECT_TRUE(e.identifiable) << e.name << ": " << e.flag;
    EXPECT_NE(r.full_report().find("wall.k_wall"), std::string::npos);
  }
}

TEST(Calibrate, FlagsAParameterTheDataDoNotSee) {
  Scene s = short_headline();
  // with droplet evaporation scaled to zero, its coefficient has no effect on anything
  s.flowsheet->set_param("droplets.multiplier", 0.0);
  auto exps = experiments({"gas.T", "bed.d50"});
  exps.resize(1);
  fill_with_model(s, exps, {});
  Stage st = two_parameter_stage();
  st.free.push_back({"droplets.k_evap", Transform::kLog, 1e-4, 1e-1, {}});
  CalibrationOptions o;
  o.profile_max_points = 2;
  const CalibrationResult r = calibrate(s, units::builtin(), exps, {st}, o);
  const auto& est = r.stages[0].estimates;
  ASSERT_EQ(est.size(), 3u);
  EXPECT_TRUE(est[0].identifiable && est[1].identifiable);
  EXPECT_FALSE(est[2].identifiable);
  EXPECT_FALSE(std::isfinite(est[2].se));
  EXPECT_NE(est[2].flag.find("do not constrain"), std::string::npos) << est[2].flag;
  const Profile* pv = nullptr;  // flagged parameters are profiled
  for (const auto& p : r.stages[0].profiles)
    if (p.name == "droplets.k_evap") pv = &p;
  ASSERT_NE(pv, nullptr);
  EXPECT_EQ(pv->verdict, "unidentifiable");
  EXPECT_FALSE(pv->bounded_below || pv->bounded_above);
  EXPECT_NE(r.brief().find("unidentifiable: droplets.k_evap"), std::string::npos) << r.brief();
}

// The penetration depth of the spray zone: below about 130 um nothing in d50 or d90 responds to it (the loss is
// flat there), near the truth (168 um) it is sharply determined.
Stage penetration_depth_stage() {
  Stage st;
  st.name = "size";
  st.free = {{"spray_zone.h_pen", Transform::kLog, 10e-6, 5e-3, {}}};
  st.observables = {"bed.d50", "bed.d90"};
  return st;
}

bool contains(const std::vector<std::string>& v, const std::string& needle) {
  for (const auto& x : v)
    if (x.find(needle) != std::string::npos) return true;
  return false;
}

TEST(Calibrate, AStartInAFlatRegionIsFoundAndLeft) {
  Scene s = short_headline();
  const double truth = s.flowsheet->param("spray_zone.h_pen");
  auto exps = experiments({"bed.d50", "bed.d90"});
  fill_with_model(s, exps, {});
  CalibrationOptions o;
  o.profile = false;
  o.flat_scan_points = 0;  // the old behaviour: stays where it started, and says why
  const std::map<std::string, double> start{{"spray_zone.h_pen", 100e-6}};
  const CalibrationResult stuck = calibrate(s, units::builtin(), exps, {penetration_depth_stage()}, o, start);
  const StageResult& a = stuck.stages[0];
  EXPECT_NEAR(stuck.parameters.at("spray_zone.h_pen"), 100e-6, 1e-9);
  ASSERT_EQ(a.flat.size(), 1u);
  EXPECT_EQ(a.flat[0], "spray_zone.h_pen");
  EXPECT_FALSE(a.moved);
  ASSERT_EQ(a.curvature.size(), 1u);
  EXPECT_LT(a.curvature[0] * std::pow(std::log(5e-3 / 10e-6), 2), o.flat_delta_chi2);
  EXPECT_GT(a.cost, 1.0);  // noise-free data: the optimum's cost is zero
  EXPECT_TRUE(contains(stuck.warnings, "stage 'size': the loss is flat in spray_zone.h_pen")) << stuck.brief();
  EXPECT_TRUE(contains(stuck.warnings, "the start lies in a flat region of the loss"));
  // with the scan: restarted from where the loss responds, and at the truth
  o.flat_scan_points = 16;
  const CalibrationResult r = calibrate(s, units::builtin(), exps, {penetration_depth_stage()}, o, start);
  const StageResult& b = r.stages[0];
  EXPECT_GE(b.restarts, 1);
  EXPECT_TRUE(b.flat.empty());
  EXPECT_NEAR(r.parameters.at("spray_zone.h_pen"), truth, 1e-3 * truth);
  EXPECT_LT(b.cost, 1e-4);
  EXPECT_GT(b.curvature[0], 1.0);
  EXPECT_TRUE(contains(r.warnings, "the loss was flat in spray_zone.h_pen")) << r.full_report();
  EXPECT_TRUE(contains(r.warnings, "restarted from there"));
  EXPECT_GT(r.simulations, stuck.simulations);  // the scan and the restart cost simulations, and are counted
}

// Droplet evaporation does not show in the gas temperature or the bed moisture from its lower bound up to about
// 0.02 kg/m2 (the droplets dry on the way at any such rate); above, it does: a plateau of the loss with edges but no
// lower point.
Stage evaporation_stage(const std::string& name) {
  Stage st;
  st.name = name;
  st.free = {{"droplets.k_evap", Transform::kLog, 1e-5, 1.0, {}}};
  st.observables = {"gas.T", "bed.moisture"};
  return st;
}

// A stage whose loss is flat in a parameter scans it, and restarts from a lower point as before; from the mere edge
// of the flat region it restarts only when no later stage frees the parameter again (that stage's descent starts
// there anyway, with data that may determine it), and the parameter goes on at its value from before the stage
// where the loss is the same there. The earlier stage says so in its notes, without a warning.
TEST(Calibrate, TheEdgeOfAFlatRegionIsLeftToALaterStageThatFreesIt) {
  Scene s = short_headline();
  auto exps = experiments({"gas.T", "bed.moisture"});
  fill_with_model(s, exps, {}, 1.03);
  CalibrationOptions o;
  o.profile = false;
  const std::map<std::string, double> start{{"droplets.k_evap", 1e-4}};
  const CalibrationResult alone = calibrate(s, units::builtin(), exps, {evaporation_stage("first")}, o, start);
  EXPECT_TRUE(contains(alone.warnings, "stage 'first': the loss was flat in droplets.k_evap")) << alone.brief();
  EXPECT_TRUE(contains(alone.warnings, "found it responding from")) << alone.brief();

  const CalibrationResult r =
      calibrate(s, units::builtin(), exps, {evaporation_stage("first"), evaporation_stage("again")}, o, start);
  ASSERT_EQ(r.stages.size(), 2u);
  const StageResult& a = r.stages[0];
  EXPECT_EQ(a.restarts, 0);
  ASSERT_EQ(a.flat.size(), 1u);
  // the descent drifted it on the plateau; it goes on at its start, where the loss is the same
  EXPECT_GT(std::abs(std::log(a.estimates[0].value / 1e-4)), 0.1) << r.full_report();
  EXPECT_TRUE(contains(a.notes,
                       "a scan over its bounds found no lower cost: the data of this stage do not determine it; it "
                       "goes on at its value from before this stage, 0.0001 kg/m2, where the loss is the same, and "
                       "stage 'again' frees it again and decides it"))
      << r.full_report();
  EXPECT_NEAR(r.stages[1].estimates[0].start, 1e-4, 1e-15);
  EXPECT_FALSE(contains(r.warnings, "stage 'first'")) << r.brief();
  EXPECT_LT(a.simulations, alone.stages[0].simulations);  // the scan, without the restart
  // from a start where the loss responds, the descent's estimate goes on: the data of the stage ruled the start out
  const CalibrationResult high =
      calibrate(s, units::builtin(), exps, {evaporation_stage("first"), evaporation_stage("again")}, o,
                {{"droplets.k_evap", 0.3}});
  ASSERT_EQ(high.stages[0].flat.size(), 1u) << high.full_report();
  EXPECT_LT(high.stages[0].estimates[0].value, 0.03);
  EXPECT_FALSE(contains(high.stages[0].notes, "goes on at its value from before")) << high.full_report();
  EXPECT_NEAR(high.stages[1].estimates[0].start, high.stages[0].estimates[0].value, 1e-12);
  // the last stage that frees it does as a single stage does
  EXPECT_TRUE(contains(r.warnings, "stage 'again': the loss was flat in droplets.k_evap")) << r.brief();
  EXPECT_TRUE(contains(r.warnings, "found it responding from")) << r.brief();
}

TEST(Calibrate, AProfileBelowTheEstimateRestartsTheStage) {
  Scene s = short_headline();
  const double truth = s.flowsheet->param("spray_zone.h_pen");
  auto exps = experiments({"bed.d50", "bed.d90"});
  fill_with_model(s, exps, {});
  CalibrationOptions o;
  o.flat_scan_points = 0;  // only the profile of the flagged estimate can find the way out
  // from 60 um (flat: the stage does not move) one profile step of a factor e^1.0116 = 2.75 each way: 21.8 um
  // (flat too) and 165 um, inside the valley of the truth (168 um; χ²/2 below 1 from 155 to 173 um)
  o.profile_max_points = 1;
  o.profile_max_offset = std::log(165.0 / 60.0);
  const CalibrationResult r =
      calibrate(s, units::builtin(), exps, {penetration_depth_stage()}, o, {{"spray_zone.h_pen", 60e-6}});
  const StageResult& st = r.stages[0];
  EXPECT_GE(st.restarts, 1);
  EXPECT_NEAR(r.parameters.at("spray_zone.h_pen"), truth, 1e-3 * truth);
  EXPECT_TRUE(contains(st.notes, "a profile found a cost lower than the estimate's")) << r.full_report();
  // the profile reported is the one around the final estimate: nothing below it
  for (const auto& p : st.profiles)
    for (double d : p.delta_chi2) EXPECT_GT(d, -o.restart_delta_chi2) << p.name;
}

TEST(Calibrate, AFailedSensitivitySolveDoesNotEndTheCalibration) {
  Scene s = short_headline();
  auto exps = experiments({"gas.T", "bed.d50"});
  fill_with_model(s, exps, {});
  CalibrationOptions o;
  o.profile = false;
  const std::map<std::string, double> start{{"wall.k_wall", 20.0}, {"bed.agg_ln_beta0", -16.8}};
  const CalibrationResult ref = calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o, start);
  EXPECT_EQ(ref.stages[0].sensitivity_retries, 0);
  // the first sensitivity solve of run1 fails: retried with smaller steps, the same answer
  std::atomic<int> calls{0};
  calibration_testing::fail_sensitivity_solve = [&](const std::string& e) { return e == "run1" && calls++ == 0; };
  const CalibrationResult once = calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o, start);
  EXPECT_EQ(once.stages[0].sensitivity_retries, 1);
  EXPECT_TRUE(contains(once.warnings, "1 sensitivity solves failed and were retried")) << once.brief();
  for (const auto& [k, v] : ref.parameters) EXPECT_NEAR(once.parameters.at(k), v, 1e-3 * std::abs(v)) << k;
  // every sensitivity solve of run1 fails: central differences of plain simulations take their place
  calibration_testing::fail_sensitivity_solve = [](const std::string& e) { return e == "run1"; };
  const CalibrationResult always = calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o, start);
  calibration_testing::fail_sensitivity_solve = nullptr;
  EXPECT_GT(always.stages[0].sensitivity_retries, 1);
  EXPECT_EQ(always.status, "ok");
  for (const auto& [k, v] : ref.parameters) EXPECT_NEAR(always.parameters.at(k), v, 1e-3 * std::abs(v)) << k;
}

// The estimates may not depend on how many threads solve the experiments: each experiment's solve is the same on
// any thread, and everything summed across experiments is summed in one order (Ceres evaluates serially).
TEST(Calibrate, TheEstimatesDoNotDependOnTheNumberOfThreads) {
  Scene s = short_headline();
  auto exps = experiments({"gas.T", "bed.d50", "bed.d90"});
  for (int c = 0; c < 2; ++c) {  // four experiments: more than the threads, so that partial sums could be regrouped
    Experiment e = exps[c];
    e.name += "_hot";
    for (auto& [name, value] : e.settings)
      if (name == "inlet.T") value += 15.0;
    exps.push_back(e);
  }
  fill_with_model(s, exps, {});
  int k = 0;  // data off the model by a few per cent, differently at every sample: a fit with residuals left
  for (auto& e : exps)
    for (auto& ob : e.observations)
      for (double& v : ob.value) v *= 1.0 + 0.03 * std::sin(1.7 * ++k);
  CalibrationOptions o;
  o.profile = false;
  std::vector<CalibrationResult> runs;
  for (int threads : {1, 2}) {
    o.num_threads = threads;
    runs.push_back(calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o,
                             {{"wall.k_wall", 20.0}, {"bed.agg_ln_beta0", -16.8}}));
  }
  ASSERT_EQ(runs[0].status, "ok") << runs[0].message;
  EXPECT_GT(runs[0].stages[0].cost, 1.0);  // residuals remain: the order of their sums shows
  for (size_t r = 1; r < runs.size(); ++r) {
    EXPECT_EQ(runs[r].stages[0].cost, runs[0].stages[0].cost) << "threads " << r + 1;
    // the costs Ceres summed at every iteration, to the bit: where these differ, an accept/reject or stopping
    // decision can go the other way and the estimates follow
    EXPECT_EQ(runs[r].stages[0].iteration_costs, runs[0].stages[0].iteration_costs) << "threads " << r + 1;
    for (const auto& [name, value] : runs[0].parameters)
      EXPECT_EQ(runs[r].parameters.at(name), value) << name << ", threads " << r + 1;
  }
}

// Two experiments of noise-free gas.T and d50 data, fitted in two parameters from a start off the truth.
struct TwoParameterFit {
  Scene s = short_headline();
  std::vector<Experiment> exps = experiments({"gas.T", "bed.d50"});
  CalibrationOptions o;  // without the profile
  TwoParameterFit() {
    fill_with_model(s, exps, {});
    o.profile = false;
  }
  CalibrationResult run() const {
    return calibrate(s, units::builtin(), exps, {two_parameter_stage()}, o,
                     {{"wall.k_wall", 20.0}, {"bed.agg_ln_beta0", -16.8}});
  }
};

TEST(Calibrate, AnInterruptEndsItAndLeavesTheNextCalibrationAsBefore) {
  TwoParameterFit fit;
  fit.o.num_threads = 2;
  const CalibrationResult before = fit.run();
  ASSERT_EQ(before.status, "ok") << before.message;
  int polls = 0;
  {
    // the poll on this thread (which solves one experiment of each evaluation) answers true at its fourth call
    InterruptScope scope([&] { return ++polls == 4; }, std::chrono::steady_clock::duration::zero());
    EXPECT_THROW(fit.run(), Interrupted);
  }
  EXPECT_EQ(polls, 4);
  const CalibrationResult after = fit.run();
  EXPECT_EQ(after.stages[0].iteration_costs, before.stages[0].iteration_costs);
  EXPECT_EQ(after.parameters, before.parameters);
}

TEST(Calibrate, ProgressReportsEveryIterationAndChangesNothing) {
  TwoParameterFit fit;
  fit.o.max_reweighting_passes = 1;
  const CalibrationResult quiet = fit.run();
  std::vector<CalibrationProgress> seen;
  fit.o.progress = [&](const CalibrationProgress& p) { seen.push_back(p); };
  const CalibrationResult watched = fit.run();
  EXPECT_EQ(watched.parameters, quiet.parameters);
  ASSERT_EQ(seen.size(), quiet.stages[0].iteration_costs.size());  // one report per Ceres iteration, its start too
  long solves = 0;
  for (size_t k = 0; k < seen.size(); ++k) {
    EXPECT_EQ(seen[k].stage, "wall_and_agglomeration");
    EXPECT_EQ(seen[k].iteration, static_cast<int>(k));
    EXPECT_EQ(seen[k].cost, quiet.stages[0].iteration_costs[k]);
    EXPECT_GE(seen[k].simulations + seen[k].sensitivity_solves, solves);  // counts only grow within a solve
    solves = seen[k].simulations + seen[k].sensitivity_solves;
  }
  EXPECT_GT(solves, 0);
}

TEST(Calibrate, DataThatNoStageUsesIsReported) {
  Scene s = short_headline();
  auto exps = experiments({"gas.T", "bed.moisture_wet"});
  fill_with_model(s, exps, {});
  Stage st;
  st.name = "wall";
  st.free = {{"wall.k_wall", Transform::kLog, 1.0, 200.0, {}}};
  st.observables = {"gas.T", "bed.moisture"};  // dry basis watched, wet basis measured
  CalibrationOptions o;
  o.profile = false;
  const auto unused = unused_observations(exps, {st});
  ASSERT_EQ(unused.size(), 1u);
  EXPECT_EQ(unused[0], "bed.moisture_wet (experiments run0, run1; 8 samples)");
  const CalibrationResult r = calibrate(s, units::builtin(), exps, {st}, o, {{"wall.k_wall", 20.0}});
  EXPECT_TRUE(contains(r.warnings, "data that no stage uses: bed.moisture_wet")) << r.brief();
  EXPECT_NE(r.brief().find("1 warning"), std::string::npos);
  // a stage without observables uses everything
  Stage all = st;
  all.observables.clear();
  EXPECT_TRUE(unused_observations(exps, {st, all}).empty());
}

TEST(Calibrate, RejectsBadConfigurationWithTheRule) {
  CalibrationOptions o;
  o.max_iterations = 0;
  try {
    o.validate();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("CalibrationOptions.max_iterations = 0: violates max_iterations >= 1"),
              std::string::npos)
        << e.what();
  }
  using Change = void (*)(CalibrationOptions&);
  for (Change bad : std::vector<Change>{[](CalibrationOptions& c) { c.flat_scan_points = 2; },
                                        [](CalibrationOptions& c) { c.max_restarts = -1; },
                                        [](CalibrationOptions& c) { c.restart_delta_chi2 = 0; },
                                        [](CalibrationOptions& c) { c.flat_delta_chi2 = -1; }}) {
    CalibrationOptions c;
    bad(c);
    EXPECT_THROW(c.validate(), ConfigError);
  }
  EXPECT_THROW(transform_from_string("ln"), ConfigError);
  EXPECT_EQ(sigma_basis_from_string(to_string(SigmaBasis::kData)), SigmaBasis::kData);
  EXPECT_EQ(jacobian_method_from_string("central_differences"), JacobianMethod::kCentralDifferences);

  Scene s = short_headline();
  auto exps = experiments({"gas.T"});
  Stage st = two_parameter_stage();
  const CalibrationOptions ok;
  // a free parameter that an experiment sets
  auto bad = exps;
  bad[0].settings.push_back({"wall.k_wall", 10.0});
  EXPECT_THROW(calibrate(s, units::builtin(), bad, {st}, ok), ConfigError);
  // a negative measured size (a sign slipped into the data): refused naming the sample, as is an absolute
  // temperature of 0 K; NaN (not measured) passes
  for (const auto& [name, value] : std::vector<std::pair<std::string, double>>{{"bed.d50", -4e-4}, {"gas.T", 0.0}}) {
    auto sizes = experiments({name});
    sizes[1].observations[0].value[2] = value;
    sizes[1].observations[0].value[0] = std::nan("");
    try {
      check_experiments(*s.flowsheet, sizes);
      FAIL() << name;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("experiment 'run1': observation " + name + ".value[2] at t = 900 s"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("value > 0"), std::string::npos) << e.what();
    }
    sizes[1].observations[0].value[2] = 1.0;
    EXPECT_NO_THROW(check_experiments(*s.flowsheet, sizes)) << name;
  }
  // an unknown observable
  auto unknown = exps;
  unknown[0].observations[0].name = "bed.d55";
  EXPECT_THROW(calibrate(s, units::builtin(), unknown, {st}, ok), ConfigError);
  // log transform needs a positive lower bound
  Stage neg = st;
  neg.free[1].transform = Transform::kLog;
  EXPECT_THROW(calibrate(s, units::builtin(), exps, {neg}, ok), ConfigError);
  // a stage whose observables no experiment has: bad input (exit 2), naming the stage and its observables
  Stage none = st;
  none.observables = {"bed.d50"};
  try {
    calibrate(s, units::builtin(), exps, {none}, ok);
    ADD_FAILURE() << "a stage without data was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bed.d50"), std::string::npos) << e.what();
  }
  EXPECT_EQ(observable_unit(*s.flowsheet, "bed.d95"), "m");
  EXPECT_EQ(observable_unit(*s.flowsheet, "gas.T"), "K");
}

}  // namespace
}  // namespace granuflow
