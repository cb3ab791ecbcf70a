// The constant-volume Monte Carlo (montecarlo/, docs/monte_carlo.md) against exact results: the constant-kernel
// population balance (Smoluchowski; Scott 1968) from monodisperse primaries, where M0 / N0 = 1 / (1 + tau / 2) and
// M2 / (N0 v0^2) = 1 + tau with tau = beta0 c0 t; results independent of the thread count and of the sample size;
// primary particles and liquid conserved through the doublings.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "granuflow/errors.hpp"
#include "mc_params.hpp"
#include "mc_statistics.hpp"

namespace mc = granuflow::montecarlo;

namespace {

mc::Config config(std::map<std::string, double> p, std::map<std::string, std::string> s) {
  return mc::make_config(p, s);
}

double at(const mc::Summary& s, const std::vector<double>& v, size_t k, int q) { return v[k * mc::kQuantities + q]; }

void expect_scott(double p_success, const std::string& seed) {
  const mc::Config c = config({{"p_success", p_success}}, {{"collisions", "constant_kernel"},
                                                           {"success", "constant"},
                                                           {"waiting_time", "exponential"},
                                                           {"sample_size", "4000"},
                                                           {"replicas", "16"},
                                                           {"seed", seed}});
  const std::vector<double> times = {0.0, 1.0, 2.0, 5.0, 10.0, 20.0};
  const mc::Summary s = mc::run(c, times);
  // A 95 % interval misses the exact value one time in twenty: of the ten comparisons at most one may lie outside
  // it, and none outside one and a half times its half-width (99.7 %).
  int misses = 0;
  for (size_t k = 0; k < times.size(); ++k) {
    const double tau = p_success * times[k];  // beta0 = c0 = 1; a success probability scales the kernel
    const double exact[2] = {1.0 / (1.0 + tau / 2.0), 1.0 + tau};
    const int q[2] = {mc::kNumber, mc::kM2};
    for (int m = 0; m < 2; ++m) {
      const double mean = at(s, s.mean, k, q[m]), half = at(s, s.hi, k, q[m]) - mean;
      SCOPED_TRACE("t = " + std::to_string(times[k]) + (m ? " M2" : " M0"));
      misses += std::abs(mean - exact[m]) > half;
      EXPECT_LE(std::abs(mean - exact[m]), 1.5 * half + 1e-15);
      // The intervals are tight enough to be a test: under 2 % of the value on either side.
      EXPECT_LT(half, 0.02 * exact[m] + 1e-15);
    }
  }
  EXPECT_LE(misses, 1);
  EXPECT_GT(s.events_per_s, 0.0);
}

}  // namespace

TEST(MonteCarlo, ConstantKernelMatchesScottWithinTheInterval) { expect_scott(1.0, "7"); }

TEST(MonteCarlo, SuccessProbabilityScalesTheKernel) { expect_scott(0.5, "11"); }

TEST(MonteCarlo, ResultDoesNotDependOnTheThreadCount) {
  std::map<std::string, std::string> s = {{"sample_size", "500"}, {"replicas", "5"}, {"imbibition", "on"}};
  const std::vector<double> times = {0.0, 5.0, 15.0};
  s["threads"] = "1";
  const mc::Summary one = mc::run(config({}, s), times);
  s["threads"] = "3";
  const mc::Summary three = mc::run(config({}, s), times);
  ASSERT_EQ(one.per_replica.size(), three.per_replica.size());
  for (size_t k = 0; k < one.per_replica.size(); ++k)
    if (!std::isnan(one.per_replica[k])) {
      EXPECT_EQ(one.per_replica[k], three.per_replica[k]) << k;
    }
  // and the replicas differ from each other (each has its own stream)
  EXPECT_NE(one.per_replica[2 * mc::kQuantities + mc::kNumber],
            one.per_replica[3 * mc::kQuantities + 2 * mc::kQuantities + mc::kNumber]);
}

TEST(MonteCarlo, KineticsDoNotDependOnTheSampleSizeButTheLiteralReadingDoes) {
  const std::vector<double> times = {0.0, 10.0, 20.0};
  auto run = [&](const std::string& n, const std::string& step) {
    return mc::run(config({}, {{"sample_size", n}, {"replicas", "8"}, {"time_step", step}}), times);
  };
  const mc::Summary small = run("400", "per_particle"), large = run("1600", "per_particle");
  for (size_t k = 1; k < times.size(); ++k) {
    const double a = at(small, small.mean, k, mc::kDMean), b = at(large, large.mean, k, mc::kDMean);
    const double ha = at(small, small.hi, k, mc::kDMean) - a, hb = at(large, large.hi, k, mc::kDMean) - b;
    EXPECT_LT(std::abs(a - b), std::hypot(ha, hb)) << "t = " << times[k];
    EXPECT_GT(a, 1.2);  // it did agglomerate
  }
  // Read literally (one collision per 1/f_coll in the whole sample), four times the sample collides four times
  // less often per particle: the larger sample has agglomerated clearly less at the same time.
  const mc::Summary lit_small = run("100", "literal"), lit_large = run("400", "literal");
  const size_t k = 2;
  EXPECT_GT(at(lit_small, lit_small.lo, k, mc::kDMean), at(lit_large, lit_large.hi, k, mc::kDMean));
}

TEST(MonteCarlo, PrimariesAndLiquidAreConservedThroughTheDoublings) {
  for (const std::string wet : {"asperity", "water_gone"}) {
    const mc::Config c = config({{"mu_exponent", 1.0}, {"r_pore", 1e-10}},
                                {{"sample_size", "400"}, {"replicas", "3"}, {"imbibition", "on"}, {"wet_until", wet}});
    const std::vector<double> times = {0.0, 2.0, 10.0, 40.0};
    const mc::Summary s = mc::run(c, times);
    EXPECT_GE(s.doublings_mean, 1.0);  // the accounting went through at least one doubling
    for (size_t k = 0; k < times.size(); ++k) {
      double fractions = 0.0;
      for (int b = 0; b < mc::kPsdBins; ++b) fractions += s.psd_mean[k * mc::kPsdBins + b];
      EXPECT_NEAR(fractions, 1.0, 1e-12);  // every primary is in exactly one agglomerate
      for (long r = 0; r < s.replicas; ++r) {
        const double* row = &s.per_replica[(static_cast<size_t>(r) * times.size() + k) * mc::kQuantities];
        const double held = row[mc::kLiquidWet] + row[mc::kLiquidBridges] + row[mc::kLiquidBlocked] +
                            row[mc::kLiquidResidual] + row[mc::kLiquidEvaporated] + row[mc::kLiquidImbibed];
        EXPECT_NEAR(held, row[mc::kLiquidAdded], 1e-12 * row[mc::kLiquidAdded] + 1e-30) << wet << " t " << k;
        if (k > 0) {
          EXPECT_GT(row[mc::kLiquidImbibed], 0.0);
          EXPECT_GT(row[mc::kLiquidEvaporated], 0.0);
        }
      }
    }
  }
}

TEST(MonteCarlo, DropletIsASphericalCapOfItsVolume) {
  const mc::Config c = config({}, {});
  const double th = c.p.theta, h = c.d.h0;
  const double a = h * std::sin(th) / (1.0 - std::cos(th));              // Eq. (7.54)
  const double cap = M_PI * h * h * (3.0 * a / std::sin(th) - h) / 3.0;  // cap of the sphere of radius a / sin
  EXPECT_NEAR(cap, c.d.V_drop, 1e-12 * c.d.V_drop);
  // It stops being wet at the asperity height: h0 - k_dry t_life = h_a (Eq. (7.55); no imbibition on glass).
  EXPECT_NEAR(c.d.h0 - c.d.k_dry * c.d.t_life, c.p.h_a, 1e-9 * c.p.h_a);
  EXPECT_NEAR(c.d.f_coll, 1.6, 1e-3);  // the glass frequency paper 003 quotes, section 7.7.3
}

TEST(MonteCarlo, BadInputIsRefusedWithOneLine) {
  EXPECT_THROW(config({{"mu_l", -1.0}}, {}), granuflow::ConfigError);
  EXPECT_THROW(config({{"viscosity", 1.0}}, {}), granuflow::ConfigError);
  EXPECT_THROW(config({}, {{"stokes_length", "both"}}), granuflow::ConfigError);
  EXPECT_THROW(config({}, {{"sample_size", "1.5"}}), granuflow::ConfigError);
  EXPECT_THROW(config({{"eps", 0.3}, {"eps_mf", 0.4}}, {}), granuflow::ConfigError);
  try {
    config({}, {{"stokes_length", "both"}});
  } catch (const granuflow::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "monte_carlo setting stokes_length = 'both': allowed are radius, diameter");
  }
}

TEST(MonteCarlo, ARunThatOutgrowsItsDropletLimitStopsWithAnError) {
  // Without drying droplets never leave; a small limit is reached early and named.
  const mc::Config c =
      config({}, {{"drying", "off"}, {"sample_size", "200"}, {"replicas", "2"}, {"max_droplets", "1000"}});
  try {
    mc::run(c, {0.0, 100.0});
    FAIL() << "no error";
  } catch (const granuflow::SolverError& e) {
    EXPECT_NE(std::string(e.what()).find("max_droplets"), std::string::npos) << e.what();
    EXPECT_GT(e.t(), 0.0);
  }
}
