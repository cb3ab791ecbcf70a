// The DEM collision kernel of paper 002 and the files it reads:
//   * the collision-count file: the example loads and gives Eq. (12); every malformed file is a ConfigError naming
//     the file, the row and the column;
//   * the kernel: grid classes take the frequency of the DEM class holding their diameter, the factored efficiency
//     reproduces Eq. (13) (step and smooth, either and both partners).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/aggregation/dem_collision.hpp"
#include "kernels/data_tables.hpp"
#include "kernels/registry.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using namespace kernels;
using testing::repo_path;

const std::string kExample = "flowsheets/data/sen2014_collisions_example.csv";

// ------------------------------------------------------------------ the collision file

TEST(DemCollisionFile, ExampleLoadsAndGivesEquation12) {
  const CollisionCounts c = read_collision_counts(repo_path(kExample));
  ASSERT_EQ(c.classes(), 6);
  EXPECT_EQ(c.dt, 1.0);
  EXPECT_EQ(c.edges.front(), 1.5e-3);
  EXPECT_EQ(c.class_of(2e-3), 0);
  EXPECT_EQ(c.class_of(2.5e-3), 1);  // an edge belongs to the class above it
  EXPECT_EQ(c.class_of(6.5e-3), 5);  // the last edge to the last class
  EXPECT_EQ(c.class_of(1e-3), -1);
  const Table t = collision_frequency_table(c);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      EXPECT_DOUBLE_EQ(t.at(i, j), c.counts[i * 6 + j] / (c.particles[i] * c.particles[j] * c.dt));
      EXPECT_EQ(t.at(i, j), t.at(j, i));
    }
  // unlike sizes collide more often than like ones (the example's shape, paper 002, Fig. A2)
  EXPECT_GT(t.at(0, 5), t.at(0, 0));
}

TEST(DemCollisionFile, EveryProblemNamesTheFileRowAndColumn) {
  const std::string head = "dt_s,0.5\nedges_m,1e-3,2e-3,3e-3\nparticles,100,50\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "counts,10,4\ncounts,4,-2\n", "row 5, column 3: count -2: collision counts must be >= 0"},
      {head + "counts,10,4\ncounts,5,2\n", "row 4, column 3: count 4 for classes 1 x 2 differs from 5 on row 5"},
      {head + "counts,10,4\n", "1 'counts' rows for 2 classes"},
      {head + "counts,10,4,1\ncounts,4,2\n", "row 4: 3 counts for 2 classes"},
      {head + "counts,10,x\ncounts,4,2\n", "row 4, column 3: 'x' is not a finite number"},
      {head + "counts,10,4\ncounts,4,nan\n", "row 5, column 3: 'nan' is not a finite number"},
      {"dt_s,0\nedges_m,1e-3,2e-3\nparticles,1\ncounts,1\n", "row 1, column 2: dt_s = 0 s"},
      {"dt_s,1\nedges_m,2e-3,1e-3\nparticles,1\ncounts,1\n", "row 2, column 3: edge 0.001 m after 0.002 m"},
      {"dt_s,1\nedges_m,1e-3,2e-3\nparticles,1,2\ncounts,1\n", "row 3: 2 particle numbers for 1 classes"},
      {"dt_s,1\nedges_m,1e-3,2e-3\nparticles,0\ncounts,3\n", "row 4, column 2: count 3 for classes 1 x 1, but class 1"},
      {"# c\ndt_s,1\nedges_m,1e-3,2e-3\nparticle,1\ncounts,1\n", "row 4, column 1: unknown key 'particle'"},
      {"dt_s,1\ndt_s,2\n", "row 2, column 1: 'dt_s' given twice (first on row 1)"},
      {"dt_s,1\nedges_m,1e-3,2e-3\ncounts,1\n", "no 'particles' row"},
  };
  for (const auto& [text, want] : cases) {
    try {
      parse_collision_counts(text, "my.csv");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ConfigError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("my.csv: ", 0), 0u) << msg;
      EXPECT_NE(msg.find(want), std::string::npos) << "got: " << msg << "\nwant: " << want;
    }
  }
  EXPECT_THROW(read_collision_counts("/nonexistent/counts.csv"), ConfigError);
}

// A collision of two particles of one class is in N_ii once or twice depending on the DEM tool: the file must say
// which (no default is safe), and a file that counts it once gets its diagonal doubled, nothing else.
TEST(DemCollisionFile, TheFileSaysHowLikeCollisionsAreCounted) {
  const std::string body = "dt_s,0.5\nedges_m,1e-3,2e-3,3e-3\nparticles,100,50\ncounts,10,4\ncounts,4,2\n";
  try {
    parse_collision_counts(body, "my.csv");
    FAIL() << "a file that does not say how it counts like collisions was accepted";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("my.csv: no 'like_collisions' row", 0), 0u) << msg;
    EXPECT_NE(msg.find("'like_collisions,twice'"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
  try {
    parse_collision_counts("like_collisions,thrice\n" + body, "my.csv");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("row 1, column 2: like_collisions takes one value"), std::string::npos);
  }
  const Table twice = collision_frequency_table(parse_collision_counts("like_collisions,twice\n" + body, "my.csv"));
  const Table once = collision_frequency_table(parse_collision_counts(body + "like_collisions,once\n", "my.csv"));
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) EXPECT_EQ(once.at(i, j), (i == j ? 2.0 : 1.0) * twice.at(i, j)) << i << j;
  EXPECT_DOUBLE_EQ(twice.at(0, 0), 10.0 / (100 * 100 * 0.5));  // Eq. (12) as printed
  // a frequency that overflows (here only once the like collisions are doubled) is named where it comes from
  const std::string huge = "dt_s,1\nedges_m,1e-3,2e-3\nparticles,1\ncounts,1e308\n";
  EXPECT_NO_THROW(parse_collision_counts("like_collisions,twice\n" + huge, "my.csv"));
  try {
    parse_collision_counts("like_collisions,once\n" + huge, "my.csv");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("my.csv: row 5, column 2: count 1e+308: the collision frequency"),
              std::string::npos)
        << e.what();
  }
}

// Spreadsheet programs write UTF-8 CSV with a byte-order mark: it is no part of the first key. Binary garbage is
// named by an escaped excerpt of what stood where a key should (a NUL in the message cut it short before).
TEST(DemCollisionFile, AByteOrderMarkIsSkippedAndGarbageIsShownEscaped) {
  const std::string text =
      "like_collisions,twice\ndt_s,0.5\nedges_m,1e-3,2e-3,3e-3\nparticles,100,50\ncounts,10,4\ncounts,4,2\n";
  const CollisionCounts plain = parse_collision_counts(text, "my.csv");
  const CollisionCounts marked = parse_collision_counts("\xEF\xBB\xBF" + text, "my.csv");
  EXPECT_EQ(marked.counts, plain.counts);
  EXPECT_EQ(marked.dt, plain.dt);
  try {
    parse_collision_counts(std::string("\x01\x00\x7f\xfe,1\n", 7), "junk.csv");
    FAIL();
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("junk.csv: row 1, column 1: unknown key '\\x01\\x00\\x7f"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\0'), std::string::npos);
  }
}

// ------------------------------------------------------------------ the DEM kernel

std::unique_ptr<AggregationKernel> dem_kernel(std::map<std::string, std::string> settings) {
  auto k = registries().aggregation.create("dem_collision");
  Settings st("test", settings);
  k->declare(st, "agg_");
  return k;
}

// Without a collision file and with no table loaded, the kernel names the setting that is missing (it reported an
// unknown data table '(none loaded)').
TEST(DemCollisionKernel, WithoutAFileOrATableTheMissingSettingIsNamed) {
  if (!table_names().empty()) GTEST_SKIP() << "a table was loaded earlier in this process";
  try {
    dem_kernel({});
    FAIL() << "a DEM kernel without collision frequencies was declared";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("test.agg_collisions_file: not given"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("none loaded"), std::string::npos) << msg;
  }
}

TEST(DemCollisionKernel, GridClassesTakeTheFrequencyOfTheirDemClass) {
  auto k = dem_kernel({{"agg_collisions_file", repo_path(kExample)}});
  const auto g = Grid::from_diameter_pivots({2e-3, 2.6e-3, 3.2e-3, 6e-3});
  ClassState<double> cs;
  cs.n = 4, cs.volume = g.pivots().data(), cs.diameter = g.diameter_pivots().data();
  const double p[3] = {0.01, 0.2, 0.02};
  k->check(cs, p, "here");
  std::vector<double> K(16);
  k->factor(cs, p, K.data());
  const Table C = collision_frequency_table(read_collision_counts(repo_path(kExample)));
  const int cls[4] = {0, 1, 2, 5};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_DOUBLE_EQ(K[i * 4 + j], 0.01 * C.at(cls[i], cls[j]));  // Eq. (11)-(12)
  const auto outside = Grid::from_diameter_pivots({2e-3, 7e-3});
  cs.n = 2, cs.volume = outside.pivots().data(), cs.diameter = outside.diameter_pivots().data();
  try {
    k->check(cs, p, "here");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sen2014_collisions_example.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("class 1"), std::string::npos) << e.what();
  }
}

TEST(DemCollisionKernel, FactoredEfficiencyReproducesEquation13) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 0.6);
  for (const char* rule : {"either", "both"})
    for (const char* shape : {"step", "smooth"}) {
      auto k =
          dem_kernel({{"agg_collisions_file", repo_path(kExample)}, {"agg_wet_rule", rule}, {"agg_efficiency", shape}});
      const double p[3] = {0.01, 0.2, 0.05};
      std::vector<double> phi(40);
      for (double& x : phi) x = u(rng);
      phi[0] = 0.2, phi[1] = 0.1999999, phi[2] = 0.2 - 1e-12;  // both sides of the step, and round-off below it
      std::vector<double> h(kMaxEfficiencyTerms * 40), sign(kMaxEfficiencyTerms);
      const int T = k->efficiency_terms(phi.data(), 40, p, h.data(), sign.data());
      ASSERT_GT(T, 0);
      for (int a = 0; a < 40; ++a)
        for (int b = 0; b < 40; ++b) {
          double e = 0;
          for (int t = 0; t < T; ++t) e += sign[t] * h[t * 40 + a] * h[t * 40 + b];
          const double ref = k->efficiency(&phi[a], &phi[b], p);
          EXPECT_NEAR(e, ref, 1e-15) << rule << " " << shape;
          if (std::string(shape) == "step") {  // Eq. (13) as printed
            const bool wa = phi[a] >= 0.2 - 1e-9, wb = phi[b] >= 0.2 - 1e-9;
            EXPECT_EQ(ref, std::string(rule) == "either" ? double(wa || wb) : double(wa && wb));
          }
        }
    }
  EXPECT_EQ(registries()
                .aggregation.create("constant")
                ->efficiency_terms(nullptr, 1, nullptr, std::vector<double>(4).data(), std::vector<double>(4).data()),
            1);
  EXPECT_EQ(registries()
                .aggregation.create("glass_transition")
                ->efficiency_terms(std::vector<double>(8).data(), 1, nullptr, std::vector<double>(4).data(),
                                   std::vector<double>(4).data()),
            0);
}

}  // namespace
}  // namespace granuflow
