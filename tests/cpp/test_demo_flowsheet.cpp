// The core against exact answers: two heated tanks in series with a mixer, a splitter and a recycle.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"
#include "units/registry.hpp"

namespace granuflow {
namespace {

constexpr double kF = 0.5, kSplit = 0.6, kM1 = 100, kM2 = 200, kQ1 = 2e4, kCp = 4180, kTa = 300, kTb = 350, kTs = 100;

std::unique_ptr<Flowsheet> demo(bool step_input = true) {
  auto fs = std::make_unique<Flowsheet>("demo");
  const auto& reg = units::builtin();
  for (auto [name, type] : {std::pair{"feed", "liquid_feed"},
                            {"mixer", "liquid_mixer"},
                            {"tank1", "stirred_tank"},
                            {"tank2", "stirred_tank"},
                            {"splitter", "liquid_splitter"},
                            {"product", "liquid_product"}})
    fs->add_unit(name, reg.create(type), Settings(name, {}));
  fs->connect("feed.out", "mixer.in1");
  fs->connect("mixer.out", "tank1.in");
  fs->connect("tank1.out", "tank2.in");
  fs->connect("tank2.out", "splitter.in");
  fs->connect("splitter.out1", "product.in");
  fs->connect("splitter.out2", "mixer.in2");
  fs->finalize();
  fs->set_param("feed.mdot", kF);
  fs->set_param("splitter.split", kSplit);
  fs->set_param("tank1.mass", kM1);
  fs->set_param("tank2.mass", kM2);
  fs->set_param("tank1.Q", kQ1);
  fs->set_param("tank1.T0", kTa);
  fs->set_param("tank2.T0", kTa);
  fs->set_param("feed.T", kTa);
  if (step_input)
    fs->set_input("feed.T", PiecewiseLinear({0, kTs}, {kTa, kTb}, PiecewiseLinear::Interp::kStep, "feed.T"));
  return fs;
}

// Exact temperatures of both tanks: x' = A x + b(T_feed), piecewise constant feed temperature.
Eigen::Vector2d exact(double t) {
  const double r = 1 - kSplit, m = kF / (1 - r);
  Eigen::Matrix2d A;
  A << -m / kM1, m * r / kM1, m / kM2, -m / kM2;
  auto b = [&](double tf) { return Eigen::Vector2d(m * (1 - r) * tf / kM1 + kQ1 / (kM1 * kCp), 0.0); };
  auto advance = [&](Eigen::Vector2d x, double dt, double tf) {
    const Eigen::Vector2d xs = -A.inverse() * b(tf);
    return Eigen::Vector2d((A * dt).exp() * (x - xs) + xs);
  };
  Eigen::Vector2d x(kTa, kTa);
  if (t <= kTs) return advance(x, t, kTa);
  return advance(advance(x, kTs, kTa), t - kTs, kTb);
}

TEST(DemoFlowsheet, TanksInSeriesWithRecycleMatchAnalyticStepResponse) {
  auto fs = demo();
  SimOptions o;
  o.t_end = 2000;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.t_out = {0, 50, 100, 150, 400, 1000, 2000};
  const SimResult r = simulate(*fs, o);
  const int i1 = fs->state_id("tank1.T"), i2 = fs->state_id("tank2.T");
  for (size_t k = 0; k < r.t.size(); ++k) {
    const auto x = exact(r.t[k]);
    EXPECT_NEAR(r.state(k, i1), x(0), 1e-6 * x(0)) << "t = " << r.t[k];
    EXPECT_NEAR(r.state(k, i2), x(1), 1e-6 * x(1)) << "t = " << r.t[k];
  }
  EXPECT_EQ(r.stats.reinits, 1);  // stopped at the feed-temperature step
}

TEST(DemoFlowsheet, ConsistentInitializationSolvesRecycleFromWrongGuesses) {
  auto fs = demo();
  SimOptions o;
  o.t_end = 10;
  const SimResult r = simulate(*fs, o);
  // The mixer outlet flow guess is 0.1 kg/s; the recycle loop fixes it to F / split at t = 0.
  EXPECT_NEAR(r.state(0, fs->state_id("mixer.mdot")), kF / kSplit, 1e-10);
  EXPECT_NEAR(r.state(0, fs->state_id("splitter.mdot2")), kF / kSplit * (1 - kSplit), 1e-10);
  EXPECT_NEAR(r.state(0, fs->state_id("mixer.T")), kTa, 1e-8);
}

TEST(DemoFlowsheet, SteadyStateOfRecycleLoopIsAnalytic) {
  auto fs = demo(false);
  fs->set_param("feed.T", kTb);
  const SteadyResult s = solve_steady_state(*fs, SteadyOptions{});
  const double r = 1 - kSplit, m = kF / kSplit;
  // T2 = T1 (tank 2 unheated); m (1 - r)(T_f - T1) + Q1/cp = 0
  const double t1 = kTb + kQ1 / (kCp * m * (1 - r));
  EXPECT_NEAR(s.y[fs->state_id("tank1.T")], t1, 1e-8);
  EXPECT_NEAR(s.y[fs->state_id("tank2.T")], t1, 1e-8);
  EXPECT_NEAR(s.y[fs->state_id("mixer.mdot")], m, 1e-12);
}

TEST(DemoFlowsheet, StopsAtBreakpointsAndIntegratesPiecewiseLinearInputExactly) {
  auto fs = demo(false);
  PiecewiseLinear mdot({0, 30, 70, 120}, {0.2, 0.8, 0.5, 0.5}, PiecewiseLinear::Interp::kLinear, "feed.mdot");
  fs->set_input("feed.mdot", mdot);
  SimOptions o;
  o.t_end = 150;
  o.t_out = {0, 30, 70, 120, 150};
  o.rtol = 1e-10;
  o.atol = 1e-12;
  const SimResult r = simulate(*fs, o);
  EXPECT_EQ(r.stats.reinits, 3);
  EXPECT_EQ(r.stats.quadratures, 3 + 3 + 1 + 1);  // feed and product: water, solids, energy; each tank's heat
  // what the sink collected (a quadrature) is the integral of the piecewise-linear feed
  const int im = testing::output_index(r, "product.balance_water_out");
  for (size_t k = 0; k < r.t.size(); ++k)
    EXPECT_NEAR(r.outputs[k * r.output_names.size() + im], mdot.integral(0, r.t[k]),
                1e-8 * std::max(1.0, mdot.integral(0, r.t[k])))
        << "t = " << r.t[k];
}

TEST(DemoFlowsheet, ForwardSensitivitiesEqualCentralDifferences) {
  const std::vector<std::string> names{"tank1.Q", "splitter.split", "tank2.mass", "tank1.T0"};
  auto fs = demo();
  SimOptions o;
  o.t_end = 600;
  o.t_out = {0, 300, 600};
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.sensitivities = names;
  const SimResult r = simulate(*fs, o);
  const int i2 = fs->state_id("tank2.T");
  const size_t nt = r.t.size(), n = r.state_names.size();
  for (size_t k = 0; k < names.size(); ++k) {
    const double p = fs->param(names[k]);
    // Richardson-extrapolated central differences: truncation O(h^4), so h can be large against the
    // integration noise of the perturbed runs.
    const double h = 4e-3 * std::abs(p);
    auto run = [&](double v) {
      auto f = demo();
      f->set_param(names[k], v);
      SimOptions q = o;
      q.sensitivities.clear();
      return simulate(*f, q).state(nt - 1, i2);
    };
    const double d1 = (run(p + h) - run(p - h)) / (2 * h);
    const double d2 = (run(p + h / 2) - run(p - h / 2)) / h;
    const double fd = (4 * d2 - d1) / 3;
    const double s = r.sens[((nt - 1) * names.size() + k) * n + i2];
    EXPECT_NEAR(s, fd, 1e-5 * std::abs(fd) + 1e-12) << names[k];
  }
}

TEST(DemoFlowsheet, JacobianEqualsFiniteDifferencesOnRandomStates) {
  auto fs = demo();
  DaeSystem sys(*fs, false);  // the feed and splitter are explicit: all states here, for the sparse path too
  const int n = sys.size();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<double> y(n), yp(n), dense(size_t(n) * n), fd, r0, r1;
    for (int i = 0; i < n; ++i) {
      y[i] = sys.scales()[i] * u(rng);
      yp[i] = 0.01 * u(rng);
    }
    const double cj = 3.7;
    sys.jacobian(10, y.data(), yp.data(), cj, dense.data(), nullptr);
    std::vector<double> sparse(sys.pattern().nnz());
    sys.jacobian(10, y.data(), yp.data(), cj, nullptr, sparse.data());
    for (int c = 0; c < n; ++c) {
      testing::central_difference_column(sys, 10, y, yp, cj, c, 1e-6 * std::max(1.0, std::abs(y[c])), fd, r0, r1);
      for (int row = 0; row < n; ++row) {
        const double ad = dense[size_t(c) * n + row];
        EXPECT_NEAR(ad, fd[row], 1e-6 * std::max(1.0, std::abs(fd[row]))) << "row " << row << " col " << c;
      }
      // The sparse values agree with the dense matrix on the pattern.
      for (int k = sys.pattern().col_ptr[c]; k < sys.pattern().col_ptr[c + 1]; ++k)
        EXPECT_DOUBLE_EQ(sparse[k], dense[size_t(c) * n + sys.pattern().row_idx[k]]);
    }
  }
}

TEST(DemoFlowsheet, BadInputNamesTheThing) {
  auto fs = demo();
  try {
    fs->set_param("tank1.mass", -5);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("tank1.mass = -5 kg"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fs->set_param("tank1.volume", 1), ConfigError);
  EXPECT_THROW(fs->set_param("tank9.mass", 1), ConfigError);
  Flowsheet open("open");
  open.add_unit("feed", units::builtin().create("liquid_feed"), Settings("feed", {}));
  open.add_unit("tank", units::builtin().create("stirred_tank"), Settings("tank", {}));
  open.connect("feed.out", "tank.in");
  try {
    open.finalize();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("tank.out"), std::string::npos) << e.what();
  }
  EXPECT_THROW(units::builtin().create("stirred_tnak"), ConfigError);
  EXPECT_THROW(Flowsheet("x").add_unit("m", units::builtin().create("liquid_mixer"), Settings("m", {{"inlet", "3"}})),
               ConfigError);
}

}  // namespace
}  // namespace granuflow
