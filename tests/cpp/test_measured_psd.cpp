// Measured size distributions (kernels/discretization/measured_psd.hpp): the kinds turn into the right cumulative
// distribution, the mapping onto a grid conserves mass exactly (number too on a number basis), reports what lies
// outside the grid, reads back as Q3 within the grid's resolution, and every bad table is refused with one line
// naming the file, row, column and value.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "granuflow/errors.hpp"
#include "kernels/discretization/grid.hpp"
#include "kernels/discretization/measured_psd.hpp"
#include "kernels/discretization/psd.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using namespace kernels;

// Log-normal Q3 (mass median d50, geometric standard deviation sg) at size d.
double lognormal_q(double d, double d50, double sg) {
  return 0.5 * std::erfc(-std::log(d / d50) / (std::log(sg) * std::sqrt(2.0)));
}

// Q3 at size s read back from the class masses of a grid (linear in ln d inside a cell, as psd.hpp reads d50).
double read_back(const Grid& g, const std::vector<double>& mass, double s) {
  const auto& d = g.diameter_edges();
  double q = 0.0;
  for (int i = 0; i < g.size(); ++i)
    q += mass[i] * (s >= d[i + 1] ? 1.0 : s <= d[i] ? 0.0 : std::log(s / d[i]) / std::log(d[i + 1] / d[i]));
  return q;
}

std::vector<double> log_sizes(double lo, double hi, int n) {
  std::vector<double> s(n);
  for (int k = 0; k < n; ++k) s[k] = lo * std::pow(hi / lo, double(k) / (n - 1));
  return s;
}

// The headline scene's grid: 10 log-spaced pivots from 50 to 1000 um.
Grid headline_grid() { return Grid::from_diameter_pivots(log_sizes(50e-6, 1000e-6, 10)); }

MeasuredPsd lognormal_table(const std::vector<double>& sizes, double d50, double sg, PsdBasis basis) {
  std::vector<double> q;
  for (double s : sizes) q.push_back(100.0 * lognormal_q(s, d50, sg));
  q.back() = 100.0;  // a measured Q ends at 100 %
  return make_measured_psd(sizes, q, basis, PsdKind::kCumulative, "test");
}

TEST(MeasuredPsd, RoundTripInsideTheGridConservesMassAndReadsBackWithinTheGridResolution) {
  const Grid g = headline_grid();
  const auto& de = g.diameter_edges();
  // 12 sizes strictly inside the grid (its edges run from 41.8 to 1196 um)
  const MeasuredPsd t = lognormal_table(log_sizes(60e-6, 1100e-6, 12), 250e-6, 1.6, PsdBasis::kMass);
  const GridPsd m = map_to_grid(t, g);
  EXPECT_EQ(m.below, 0.0);
  EXPECT_EQ(m.above, 0.0);
  double sum = 0.0;
  for (double x : m.mass) sum += x;
  EXPECT_NEAR(sum, 1.0, 1e-15);  // the cells hold the whole measured mass
  const Cumulative c = cumulative(t);
  double worst = 0.0;
  for (size_t k = 0; k < t.sizes.size(); ++k) {
    const double s = t.sizes[k], back = read_back(g, m.mass, s);
    // exact at every grid edge, and between edges off by less than the mass of the cell holding s
    const int cell = g.cell_of(volume_of_diameter(s));
    ASSERT_GE(cell, 0);
    EXPECT_LE(std::abs(back - c.Q[k]), m.mass[cell]) << "size " << s;
    worst = std::max(worst, std::abs(back - c.Q[k]));
  }
  for (size_t i = 0; i < de.size(); ++i) EXPECT_NEAR(read_back(g, m.mass, de[i]), c.at(de[i]), 1e-15);
  // the 10-class grid's resolution: Q3 read back within 0.03 at the measured sizes
  EXPECT_LT(worst, 0.03);
  std::printf("round trip (10 classes, 12 sizes inside): largest |Q3 read back - Q3 measured| = %.6f\n", worst);
  // a finer grid over the same range reads back closer
  const Grid fine = Grid::from_diameter_pivots(log_sizes(50e-6, 1000e-6, 37));
  const GridPsd mf = map_to_grid(t, fine);
  double worst_fine = 0.0;
  for (size_t k = 0; k < t.sizes.size(); ++k)
    worst_fine = std::max(worst_fine, std::abs(read_back(fine, mf.mass, t.sizes[k]) - c.Q[k]));
  EXPECT_LT(worst_fine, worst / 3);
}

TEST(MeasuredPsd, MassOutsideTheGridIsReportedAndFoldedIntoTheEndClasses) {
  const Grid g = headline_grid();
  const auto& de = g.diameter_edges();
  const MeasuredPsd t = lognormal_table(log_sizes(20e-6, 3000e-6, 15), 300e-6, 2.0, PsdBasis::kMass);
  const Cumulative c = cumulative(t);
  const GridPsd m = map_to_grid(t, g);
  // the table's own Q (linear in ln d between its sizes) at the first and last edge
  auto q_at = [&](double s) {
    size_t k = 0;
    while (t.sizes[k + 1] <= s) ++k;
    return (t.values[k] +
            (t.values[k + 1] - t.values[k]) * std::log(s / t.sizes[k]) / std::log(t.sizes[k + 1] / t.sizes[k])) /
           100.0;
  };
  EXPECT_NEAR(m.below, q_at(de.front()), 1e-15);
  EXPECT_NEAR(m.above, 1.0 - q_at(de.back()), 1e-15);
  EXPECT_GT(m.below, 1e-3);
  EXPECT_GT(m.above, 1e-2);
  EXPECT_NEAR(m.mass.front(), c.at(de[1]), 1e-15);                   // the cell plus everything below it
  EXPECT_NEAR(m.mass.back(), 1.0 - c.at(de[de.size() - 2]), 1e-15);  // the cell plus everything above it
  double sum = 0.0;
  for (double x : m.mass) sum += x;
  EXPECT_NEAR(sum, 1.0, 1e-15);
  std::printf("outside the grid: below %.6f, above %.6f of the measured mass\n", m.below, m.above);
}

TEST(MeasuredPsd, NumberBasisConservesNumberExactlyAndGivesMassWithThePivots) {
  const Grid g = headline_grid();
  const auto& de = g.diameter_edges();
  const MeasuredPsd t = lognormal_table(log_sizes(60e-6, 1100e-6, 10), 150e-6, 1.5, PsdBasis::kNumber);
  const Cumulative c = cumulative(t);
  const GridPsd m = map_to_grid(t, g);
  ASSERT_EQ(m.number.size(), size_t(g.size()));
  double n = 0.0, v = 0.0;
  for (int i = 0; i < g.size(); ++i) {
    EXPECT_NEAR(m.number[i], c.at(de[i + 1]) - c.at(de[i]), 1e-15);  // number fractions of the table, exactly
    n += m.number[i], v += m.number[i] * g.pivot(i);
  }
  EXPECT_NEAR(n, 1.0, 1e-15);
  for (int i = 0; i < g.size(); ++i) EXPECT_NEAR(m.mass[i], m.number[i] * g.pivot(i) / v, 1e-15);
  // a unit given total mass M puts N_i = M m_i / (rho x_i) particles in class i: the table's number fractions
  for (int i = 0; i < g.size(); ++i) EXPECT_NEAR(m.mass[i] / g.pivot(i) / (1.0 / v), m.number[i], 1e-14);
}

TEST(MeasuredPsd, KindsTurnIntoTheSameCumulativeDistribution) {
  // sieves 100, 200, 400 um with the pan: 10, 30, 40, 20 % retained
  const MeasuredPsd r =
      make_measured_psd({0.0, 100e-6, 200e-6, 400e-6}, {10, 30, 40, 20}, PsdBasis::kMass, PsdKind::kRetained, "sieve");
  const Cumulative c = cumulative(r);
  ASSERT_EQ(c.d.size(), 4u);
  EXPECT_DOUBLE_EQ(c.d.back(), 800e-6);  // the top sieve's class ends at the same size ratio
  EXPECT_NEAR(c.Q[0], 0.1, 1e-15);       // the pan lies just below the first sieve
  EXPECT_NEAR(c.Q[1], 0.4, 1e-15);
  EXPECT_NEAR(c.Q[2], 0.8, 1e-15);
  EXPECT_EQ(c.Q[3], 1.0);
  EXPECT_EQ(c.at(99e-6), 0.0);
  EXPECT_NEAR(c.at(std::sqrt(100e-6 * 200e-6)), 0.25, 1e-15);  // linear in ln d
  // the same as a density q (per m) over the classes 100-200-400-800 um, without the pan
  const MeasuredPsd q =
      make_measured_psd({100e-6, 200e-6, 400e-6, 800e-6}, {0.4 / 100e-6, 0.4 / 200e-6, 0.2 / 400e-6, 0},
                        PsdBasis::kVolume, PsdKind::kDensity, "q3");
  const Cumulative cq = cumulative(q);
  EXPECT_NEAR(cq.Q[1], 0.4, 1e-15);
  EXPECT_NEAR(cq.Q[2], 0.8, 1e-15);
}

TEST(MeasuredPsd, CsvFileWithUnitsBomAndComments) {
  const std::string text = "\xEF\xBB\xBF# made-up sieve analysis\nsize_um,retained\n0,5\n100,25\n200,50\n\n400,20\n";
  const MeasuredPsd t = parse_measured_psd(text, "bed.csv");
  EXPECT_EQ(t.kind, PsdKind::kRetained);
  EXPECT_EQ(t.basis, PsdBasis::kMass);
  ASSERT_EQ(t.sizes.size(), 4u);
  EXPECT_DOUBLE_EQ(t.sizes[3], 400e-6);
  EXPECT_EQ(t.rows[3], 7);  // the file's line
  const MeasuredPsd q = parse_measured_psd("size_mm,q3\n0.1,4\n0.2,3\n0.4,0\n", "q.csv");
  EXPECT_DOUBLE_EQ(q.values[0], 4000.0);  // per mm -> per m
  EXPECT_EQ(q.basis, PsdBasis::kVolume);
}

void expect_refused(const std::string& text, const std::string& part) {
  try {
    parse_measured_psd(text, "bad.csv");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(part), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;  // one line
    EXPECT_EQ(m.rfind("bad.csv: ", 0), 0u) << m;      // naming the file first
  }
}

TEST(MeasuredPsd, BadTablesAreRefusedWithOneLineNamingRowColumnAndValue) {
  expect_refused("size_um,Q3\n100,0.2\n200,0.6\n300,0.5\n400,1\n", "row 4, column 2 (Q3): Q decreases from 0.6 to 0.5");
  expect_refused("size_um,retained\n100,-5\n200,60\n400,45\n", "row 2, column 2 (retained): value -5 is negative");
  expect_refused("size_um,Q3\n100,0.2\n100,0.6\n400,1\n", "row 3, column 1 (size): size 0.0001 m does not increase");
  expect_refused("size_um,Q3\n200,0.2\n100,0.6\n400,1\n", "row 3, column 1 (size)");
  expect_refused("size_um,Q3\n100,0.2\n200,0.6\n400,0.9\n", "the last Q is 0.9: neither 1 nor 100 %");
  expect_refused("size_um,retained\n100,20\n200,60\n400,30\n", "the sum of the retained amounts is 110");
  expect_refused("size_um,Q3\n100,0.2\n200,nan\n400,1\n", "row 3, column 2 (Q3): value nan is not a finite number");
  expect_refused("size_um,q3\n100,0.004\n200,0.002\n400,0.001\n", "its value must be 0");
  expect_refused("size_um,Q3\n100,abc\n", "'abc' is not a number");
  expect_refused("diameter,Q3\n100,0.5\n", "not a size column");
  expect_refused("size_um,Q9\n100,0.5\n", "not a value column");
  expect_refused("size_um,Q3\n100,1\n", "at least two sizes");
  expect_refused("size_um,Q3\n0,0\n100,1\n", "size 0 is not positive");
  // a total within 0.5 % of 100 is accepted (and renormalized)
  EXPECT_NO_THROW(parse_measured_psd("size_um,retained\n100,20\n200,60\n400,20.4\n", "ok.csv"));
  // arrays: the same checks, rows counted from 1
  try {
    make_measured_psd({1e-4, 2e-4}, {0.5, -0.1}, PsdBasis::kMass, PsdKind::kRetained, "arrays");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("arrays: row 2, column 2"), std::string::npos) << e.what();
  }
}

TEST(MeasuredPsd, ShippedExampleLoads) {
  const MeasuredPsd t = read_measured_psd(testing::repo_path("flowsheets/data/gf25_example_sieve_start.csv"));
  EXPECT_EQ(t.kind, PsdKind::kRetained);
  const GridPsd m = map_to_grid(t, headline_grid());
  double sum = 0.0;
  for (double x : m.mass) sum += x;
  EXPECT_NEAR(sum, 1.0, 1e-15);
}

}  // namespace
}  // namespace granuflow
