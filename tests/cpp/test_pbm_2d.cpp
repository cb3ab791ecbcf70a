// The 2-D population balance over solid x liquid volume (paper 002) with its DEM kernel (test_dem_collisions.cpp):
//   * the engine: the FFT convolution equals the pair loop; aggregation conserves number (one per event), solid and
//     liquid volume to round-off.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/aggregation/dem_collision.hpp"
#include "kernels/data_tables.hpp"
#include "kernels/population/population2d.hpp"
#include "kernels/registry.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using namespace kernels;
using testing::repo_path;

const std::string kExample = "flowsheets/data/sen2014_collisions_example.csv";

// ------------------------------------------------------------------ the engine

struct Engine {
  UnitSpec spec;
  Population2D pop;
  Population2D::WorkPtr work;
  std::vector<double> p;
  Engine(const Grid& solid, int nl, double dl, std::map<std::string, std::string> settings) {
    Settings st("test", settings);
    pop.declare(spec, st, std::make_shared<const Grid2D>(std::make_shared<const Grid>(solid), nl, dl), {});
    for (const auto& s : spec.params()) p.push_back(s.value);
    work = pop.make_work();
    pop.configure(*work, p.data(), "test");
  }
};

std::vector<double> random_numbers(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> N(n);
  for (double& x : N) x = u(rng) < 0.2 ? 0.0 : 1e3 * u(rng);
  return N;
}

TEST(Population2D, ConvolutionEqualsThePairLoop) {
  const auto g = Grid::from_diameter_pivots({2e-3, 2.3e-3, 2.7e-3, 3.1e-3, 3.6e-3, 4.2e-3, 5e-3});
  const double dl = 0.3 * g.pivot(0);
  for (auto settings : std::vector<std::map<std::string, std::string>>{
           {{"aggregation", "dem_collision"}, {"agg_collisions_file", repo_path(kExample)}},
           {{"aggregation", "dem_collision"},
            {"agg_collisions_file", repo_path(kExample)},
            {"agg_wet_rule", "both"},
            {"agg_efficiency", "smooth"}},
           {{"aggregation", "sum"}}}) {
    Engine e(g, 9, dl, settings);
    ASSERT_TRUE(e.pop.convolution());
    const int n = e.pop.size();
    const auto N = random_numbers(n, 3);
    std::vector<double> a(n, 0.0), b(n, 0.0), oa(kOut2Rows, 0.0), ob(kOut2Rows, 0.0);
    e.pop.aggregation_rates(*e.work, N.data(), e.p.data(), a.data(), oa.data());
    e.pop.aggregation_direct(*e.work, N.data(), e.p.data(), b.data(), ob.data());
    double scale = 0;
    for (double v : b) scale = std::max(scale, std::abs(v));
    ASSERT_GT(scale, 0.0);
    for (int k = 0; k < n; ++k) EXPECT_NEAR(a[k], b[k], 1e-12 * scale) << settings["aggregation"] << " bin " << k;
    for (int k = 0; k < kOut2Rows; ++k) EXPECT_NEAR(oa[k], ob[k], 1e-12 * std::abs(ob[k]) + 1e-14 * scale);
    EXPECT_GT(ob[kOut2Number], 0.0);  // the test reaches the liquid axis' end
  }
}

// Number falls by one per event, solid and liquid volume stay, to round-off (paper 002, Eqs. (8)-(10)).
TEST(Population2D, AggregationConservesNumberSolidAndLiquidVolume) {
  const auto g = Grid::geometric(4e-9, 3, 12);
  for (const char* ev : {"convolution", "direct"}) {
    Engine e(g, 11, 1.5e-9,
             {{"aggregation", "dem_collision"},
              {"agg_collisions_file", repo_path(kExample)},
              {"aggregation_evaluation", ev}});
    const Grid2D& g2 = e.pop.grid();
    const int n = g2.size();
    const auto N = random_numbers(n, 11);
    std::vector<double> dN(n, 0.0), out(kOut2Rows, 0.0), d(n);
    e.pop.aggregation_rates(*e.work, N.data(), e.p.data(), dN.data(), out.data());
    e.pop.death_rates(*e.work, N.data(), e.p.data(), d.data());
    double number = out[kOut2Number], solid = out[kOut2Solid], liquid = out[kOut2Liquid], events = 0, ds = 0, dli = 0;
    for (int a = 0; a < n; ++a) {
      number += dN[a], solid += g2.solid_volume(a) * dN[a], liquid += g2.liquid_volume(a) * dN[a];
      events += 0.5 * N[a] * d[a];
      ds += g2.solid_volume(a) * N[a] * d[a], dli += g2.liquid_volume(a) * N[a] * d[a];
    }
    ASSERT_GT(events, 0.0);
    EXPECT_NEAR(number, -events, 1e-13 * events) << ev;
    EXPECT_NEAR(solid, 0.0, 1e-14 * ds) << ev;
    EXPECT_NEAR(liquid, 0.0, 1e-14 * dli) << ev;
    EXPECT_GT(out[kOut2Liquid], 0.0);
  }
}

}  // namespace
}  // namespace granuflow
