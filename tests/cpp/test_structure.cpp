// Structural and numerical singularity of the algebraic equations (structure.hpp): the matching on known
// graphs, and flowsheets refused before consistent initialization with the loop named.
#include <gtest/gtest.h>

#include "granuflow/errors.hpp"
#include "granuflow/structure.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

TEST(Structure, MatchingIsMaximumWhereGreedyChoicesBlock) {
  // Row 0 could take column 0 or 1, row 1 only column 0: a greedy first choice (0 -> 0) must be undone.
  const std::vector<std::vector<int>> adj{{0, 1}, {0}, {1, 2}};
  const Matching m = maximum_matching(3, adj);
  EXPECT_EQ(m.size, 3);
  EXPECT_EQ(m.row_col[1], 0);
  EXPECT_EQ(m.row_col[0], 1);
  EXPECT_EQ(m.row_col[2], 2);
  for (int r = 0; r < 3; ++r) EXPECT_EQ(m.col_row[m.row_col[r]], r);
}

TEST(Structure, LongAugmentingChainNeedsNoRecursion) {
  // Row k holds columns k and k+1, the last row only column 0: one augmenting path through every row.
  const int n = 200000;
  std::vector<std::vector<int>> adj(n);
  for (int k = 0; k + 1 < n; ++k) adj[k] = {k, k + 1};
  adj[n - 1] = {0};
  EXPECT_EQ(maximum_matching(n, adj).size, n);
}

TEST(Structure, DulmageMendelsohnNamesTheDeficientPart) {
  // Rows 0 and 1 both hold only column 0; column 1 appears in no row; row 2 <-> column 2 is fine.
  const std::vector<std::vector<int>> adj{{0}, {0}, {2}};
  const Matching m = maximum_matching(3, adj);
  EXPECT_EQ(m.size, 2);
  const Deficiency d = structural_deficiency(3, adj, m);
  EXPECT_EQ(d.cols, (std::vector<int>{1}));
  EXPECT_EQ(d.rows, (std::vector<int>{0, 1}));
}

const char* kLoop = R"(
scene: loop
t_end: 100 s
units:
  feed: {type: liquid_feed, params: {mdot: 0.5 kg/s}}
  mixer: {type: liquid_mixer}
  splitter: {type: liquid_splitter, params: {split: 0.6}}
  product: {type: liquid_product}
connections:
  - feed.out -> mixer.in1
  - mixer.out -> splitter.in
  - splitter.out1 -> product.in
  - splitter.out2 -> mixer.in2
)";

TEST(Structure, RecycleWithoutHoldUpRunsDenseAndIsNamedWhereItCannotStart) {
  // A loop of algebraic units that returns part of its flow has a solution, mixer = feed / split. Dense, the
  // splitter (explicit) is evaluated inside the mixer's equations and consistent initialization finds it.
  Scene dense = scene_from_text(kLoop);
  dense.options.linear_solver = LinearSolverChoice::kDense;
  const SimResult r = simulate(*dense.flowsheet, dense.options);
  EXPECT_NEAR(r.state(r.t.size() - 1, dense.flowsheet->state_id("mixer.mdot")), 0.5 / 0.6, 1e-9);
  // Sparse, the splitter's own guesses (0.1 kg/s out of 0.1 kg/s) make the mixing equations singular at the
  // start, where IDACalcIC used to fail blaming mixer.mdot; the loop is named instead, with the way out.
  Scene sparse = scene_from_text(kLoop);
  sparse.options.linear_solver = LinearSolverChoice::kSparse;
  try {
    simulate(*sparse.flowsheet, sparse.options);
    FAIL() << "the sparse run started from a singular point";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    for (const char* name : {"flowsheet 'loop'", "mixer.T", "mixer.w", "at the initial state", "linear_solver: dense"})
      EXPECT_NE(m.find(name), std::string::npos) << name << " not in: " << m;
  }
}

TEST(Structure, RecycleReturningAllItsFlowIsRefusedNamingTheLoop) {
  // split = 0: every kg/s leaving the mixer comes back to it, mixer.mdot = feed + mixer.mdot has no solution.
  std::string text = kLoop;
  text.replace(text.find("split: 0.6"), 10, "split: 0.0");
  for (const char* solver : {"dense", "sparse"}) {
    Scene s = scene_from_text(text);
    s.options.linear_solver = parse_linear_solver(solver);
    try {
      simulate(*s.flowsheet, s.options);
      FAIL() << "a total recycle without hold-up ran (" << solver << ")";
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      for (const char* name :
           {"flowsheet 'loop'", "mixer.mdot", "splitter.mdot2", "units mixer, splitter", "split fractions", "hold-up"})
        EXPECT_NE(m.find(name), std::string::npos) << name << " not in: " << m;
      EXPECT_EQ(m.find("feed."), std::string::npos) << m;         // the feed is not part of the loop
      EXPECT_EQ(m.find("structurally"), std::string::npos) << m;  // another split would run
    }
  }
}

TEST(Structure, ShippedScenesPass) {
  for (const char* f :
       {"flowsheets/demo_tanks.yaml", "flowsheets/stoeckl_gf25_batch.yaml", "flowsheets/pbm_constant_kernel.yaml"}) {
    Scene s = scene_from_file(f);
    for (bool inlined : {false, true}) {
      DaeSystem sys(*s.flowsheet, inlined);
      EXPECT_NO_THROW(check_algebraic_structure(sys)) << f;
    }
  }
}

}  // namespace
}  // namespace granuflow
