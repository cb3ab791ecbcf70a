// Grids, PSD statistics, initial binning and the kernel registries: every registered plugin declares its
// parameters with checked SI units and bounds; kernels evaluate to finite, symmetric, non-negative values;
// unknown names are ConfigErrors listing the valid ones; a callable kernel (the Python prototyping path)
// reproduces the compiled one; parameter sensitivities flow through the kernels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"
#include "kernels/aggregation/callback.hpp"
#include "kernels/aggregation/dem_collision.hpp"
#include "kernels/data_tables.hpp"
#include "kernels/discretization/initial_distribution.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/registry.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"

namespace granuflow {
namespace {

using namespace kernels;

TEST(PbmGrid, GeometricGridHasRatioTwoToTheOneOverQ) {
  for (int q : {1, 2, 3, 5}) {
    const auto g = Grid::geometric(std::exp2(-12.0), q, 9 * q);
    for (int i = 0; i < g.size(); ++i) {
      EXPECT_NEAR(g.edge(i + 1) / g.edge(i), std::exp2(1.0 / q), 1e-14);
      EXPECT_DOUBLE_EQ(g.pivot(i), 0.5 * (g.edge(i) + g.edge(i + 1)));
      EXPECT_NEAR(g.diameter_pivots()[i], std::cbrt(6 * g.pivot(i) / pbm_analytic::kPi),
                  1e-15 * g.diameter_pivots()[i]);
      EXPECT_EQ(g.cell_of(g.pivot(i)), i);
      EXPECT_EQ(g.interval_of(g.pivot(i)), i);
    }
    EXPECT_EQ(g.edge(q), std::exp2(-11.0));  // exact powers of two
  }
  const auto g1 = Grid::geometric(1.0, 1, 5);
  EXPECT_EQ(g1.pivot(0) + g1.pivot(0), g1.pivot(1));  // q = 1: equal partners land exactly on a pivot
  EXPECT_EQ(g1.cell_of(0.5), -1);
  EXPECT_EQ(g1.cell_of(32.0), 5);
  EXPECT_EQ(g1.interval_of(g1.upper_virtual()), 5);
  EXPECT_THROW(Grid::geometric(1.0, 0, 5), ConfigError);
  EXPECT_THROW(Grid::geometric(-1.0, 1, 5), ConfigError);
  EXPECT_THROW(Grid::from_pivots({1.0, 0.5, 2.0}), ConfigError);
  const auto gp = Grid::from_diameter_pivots({50e-6, 100e-6, 200e-6, 400e-6});
  EXPECT_NEAR(gp.diameter_pivots()[0], 50e-6, 1e-18);
  EXPECT_NEAR(gp.diameter_edges()[1], std::sqrt(50e-6 * 100e-6), 1e-15);
}

// A grid whose end pivots' squares leave the doubles gave NaN rates at t = 0 (a doubling grid of 525 classes from
// 2^-12 m3); it is refused naming the pivot, and the largest grid within range still has finite virtual pivots.
TEST(PbmGrid, AGridBeyondTheRangeOfItsSquaredVolumesIsRefused) {
  const auto last = Grid::geometric(std::exp2(-12.0), 1, 524);
  EXPECT_TRUE(std::isfinite(last.upper_virtual()) && last.upper_virtual() > last.pivots().back());
  try {
    Grid::geometric(std::exp2(-12.0), 1, 525);
    FAIL() << "a grid reaching 2e154 m3 was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("grid pivot 524"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Grid::from_pivots({1e-160, 1e-150, 1e-140}), ConfigError);  // the lower virtual pivot underflows
}

TEST(PbmGrid, CharacteristicDiametersInterpolateTheCumulativeMassInLogD) {
  const auto g = Grid::geometric(1.0, 1, 4);
  std::vector<double> N(4, 0.0);
  N[2] = 1.0 / g.pivot(2);  // all mass in class 2
  const double d2 = g.diameter_edges()[2], d3 = g.diameter_edges()[3];
  EXPECT_NEAR(characteristic_diameter(g, N.data(), 0.5), std::sqrt(d2 * d3), 1e-14 * d3);
  EXPECT_NEAR(characteristic_diameter(g, N.data(), 0.1), d2 * std::pow(d3 / d2, 0.1), 1e-14 * d3);
  // A fine grid reproduces the median of a log-normal mass distribution.
  const auto f = Grid::from_diameter_pivots([] {
    std::vector<double> d;
    for (int i = 0; i < 200; ++i) d.push_back(20e-6 * std::pow(100.0, i / 199.0));
    return d;
  }());
  std::vector<double> num(f.size()), vol(f.size()), M(f.size());
  lognormal_mass_cells(f, 1e-3, 300e-6, 1.4, num.data(), vol.data());
  bin_cells(f, Binning::kMass, num.data(), vol.data(), M.data());
  EXPECT_NEAR(characteristic_diameter(f, M.data(), 0.5), 300e-6, 1e-3 * 300e-6);
  const double s = std::log(1.4), z = 1.2815515655446004;  // Phi^-1(0.9)
  EXPECT_NEAR(characteristic_diameter(f, M.data(), 0.9), 300e-6 * std::exp(z * s), 2e-3 * 300e-6);
  EXPECT_NEAR(volume_moment(f, M.data(), 1), 1e-3, 1e-9);
}

TEST(PbmGrid, SeveralCharacteristicDiametersAtOnceEqualEachAlone) {
  // The batched form shares the cumulative distribution between fractions given in any order; each result must be
  // the one-fraction form's to the bit, including the exact edge (x = Q3 at an edge), the top class and NaN when
  // the population is empty. Class 0 below zero counts as empty.
  const auto g = Grid::geometric(1.0, 1, 6);
  const std::vector<double> d = g.diameter_edges();
  const std::vector<double> m = {-1e-3, 0.2, 0.0, 0.3, 0.5, 1e-12};
  const double x[] = {0.9, 0.2, 0.5, 0.999999999999, 0.05, 0.2 / 1.0};
  double out[6];
  characteristic_diameters_of_mass(d, m.data(), x, 6, out);
  // The definition written out: Q3 at the edges, the first cell whose upper edge reaches x, log-linear inside it.
  auto reference = [&](double xk) {
    std::vector<double> q(7, 0.0);
    for (int i = 0; i < 6; ++i) q[i + 1] = q[i] + std::max(m[i], 0.0);
    for (int i = 0; i < 6; ++i) {
      const double lo = q[i] / q[6], hi = q[i + 1] / q[6];
      if (hi >= xk && hi > lo) return d[i] * std::pow(d[i + 1] / d[i], (xk - lo) / (hi - lo));
    }
    return d[6];
  };
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(out[k], reference(x[k])) << k;
    EXPECT_EQ(out[k], characteristic_diameter_of_mass(d, m.data(), x[k])) << k;
  }
  EXPECT_NEAR(out[1], d[3], 1e-9 * d[3]);  // Q3 = 0.2 (up to the 1e-12 in the top class) from d[2] to d[3]: empty
  EXPECT_GT(out[0], d[4]);
  EXPECT_LT(out[0], d[5]);
  const std::vector<double> none(6, 0.0);
  characteristic_diameters_of_mass(d, none.data(), x, 2, out);
  EXPECT_TRUE(std::isnan(out[0]) && std::isnan(out[1]));
  EXPECT_THROW(characteristic_diameters_of_mass(d, m.data(), std::vector<double>{0.5, 1.0}.data(), 2, out),
               granuflow::ConfigError);
}

TEST(PbmGrid, MomentBinningKeepsNumberAndVolumeOfTheCells) {
  const auto g = Grid::geometric(std::exp2(-12.0), 2, 54);
  std::vector<double> num(g.size()), vol(g.size()), N(g.size());
  exponential_cells(g, 1.0, 1.0, num.data(), vol.data());
  bin_cells(g, Binning::kMoments, num.data(), vol.data(), N.data());
  double n_cells = 0, v_cells = 0;
  for (int i = 0; i < g.size(); ++i) n_cells += num[i], v_cells += vol[i];
  // Exact cell integrals: number above 2^-12 and the volume of exp(-v).
  EXPECT_NEAR(n_cells, std::exp(-std::exp2(-12.0)), 1e-14);
  EXPECT_NEAR(v_cells, (1 + std::exp2(-12.0)) * std::exp(-std::exp2(-12.0)), 1e-13);
  EXPECT_NEAR(volume_moment(g, N.data(), 1) / v_cells, 1.0, 1e-14);
  // The number moves only where the lowest cell's packet reaches below the first pivot.
  EXPECT_NEAR(volume_moment(g, N.data(), 0) / n_cells, 1.0, 1e-6);
}

template <class K>
void expect_declared(const Registry<K>& reg) {
  for (const auto& name : reg.names()) {
    EXPECT_FALSE(reg.description(name).empty()) << name;
    const auto k = reg.create(name);
    for (const auto& p : k->params()) {
      EXPECT_TRUE(is_known_si_unit(p.unit)) << name << "." << p.name << " unit " << p.unit;
      EXPECT_LE(p.lower, p.value) << name << "." << p.name;
      EXPECT_LE(p.value, p.upper) << name << "." << p.name;
      EXPECT_FALSE(p.description.empty()) << name << "." << p.name;
    }
  }
}

TEST(PbmKernels, EveryRegisteredPluginDeclaresItsParameters) {
  auto& r = registries();
  expect_declared(r.aggregation);
  expect_declared(r.selection);
  expect_declared(r.fragments);
  expect_declared(r.growth);
  for (const char* name :
       {"constant", "sum", "product", "kapur", "eke", "shear", "dem_collision", "stokes", "glass_transition"})
    EXPECT_TRUE(r.aggregation.contains(name)) << name;
  for (const char* name : {"linear", "power_law", "vogel_peukert"}) EXPECT_TRUE(r.selection.contains(name));
  for (const char* name : {"uniform_binary", "power_law", "tanh_power_law"}) EXPECT_TRUE(r.fragments.contains(name));
  for (const char* name : {"constant", "surface_proportional", "moment_based"}) EXPECT_TRUE(r.growth.contains(name));
  try {
    r.aggregation.create("constnat");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("constant, dem_collision, eke"), std::string::npos) << e.what();
  }
  EXPECT_THROW(pbm_test::flowsheet({{"aggregation", "golovin"}}), ConfigError);
  EXPECT_THROW(pbm_test::flowsheet({{"aggregation", "sum"}, {"aggregation_scheme", "moving_pivot"}}), ConfigError);
  // sum lambda_k = 1 (paper 003, Eq. (7.36)) is checked when a run starts.
  auto fs = pbm_test::flowsheet({{"growth", "moment_based"}}, {{"growth_lambda_0", 0.5}});
  EXPECT_THROW(pbm_test::run(*fs, {0, 1}), ConfigError);
}

TEST(PbmKernels, AggregationKernelsAreSymmetricFiniteAndNonNegative) {
  const auto g = Grid::from_diameter_pivots({60e-6, 120e-6, 250e-6, 500e-6, 1000e-6});
  set_table("test_collisions",
            collision_frequency_table(std::vector<double>(25, 10.0), std::vector<double>(5, 1e3), 0.5, "test"));
  std::vector<double> X(5, 0.05), T(5, 330.0), LC{0.1, 0.3, 0.1, 0.3, 0.5};
  ClassState<double> cs;
  cs.n = 5, cs.volume = g.pivots().data(), cs.diameter = g.diameter_pivots().data();
  cs.fields[0] = X.data(), cs.fields[1] = X.data(), cs.fields[2] = T.data(), cs.fields[3] = LC.data();
  cs.fields[4] = LC.data();  // wetted fraction
  for (const auto& name : registries().aggregation.names()) {
    auto k = registries().aggregation.create(name);
    Settings st("test", {{"agg_collisions", "test_collisions"}});
    k->declare(st, "agg_");
    std::vector<double> p, beta(25);
    for (const auto& s : k->params()) p.push_back(s.value);
    k->beta(cs, p.data(), beta.data());
    double beta_max = 0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) {
        EXPECT_TRUE(std::isfinite(beta[i * 5 + j]) && beta[i * 5 + j] >= 0) << name;
        EXPECT_EQ(beta[i * 5 + j], beta[j * 5 + i]) << name;
        beta_max = std::max(beta_max, beta[i * 5 + j]);
      }
    EXPECT_GT(beta_max, 0.0) << name << ": a kernel that never aggregates passes the checks above";
    // The textbook kernels by their definitions, at the defaults beta0 = 1 1/s, v_ref = 1 m^3.
    const double* v = g.pivots().data();
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) {
        const double b = beta[i * 5 + j];
        if (name == "constant") {
          EXPECT_EQ(b, 1.0);
        } else if (name == "sum") {
          EXPECT_NEAR(b, v[i] + v[j], 1e-14 * (v[i] + v[j])) << i << " " << j;
        } else if (name == "product") {
          EXPECT_NEAR(b, v[i] * v[j], 1e-14 * v[i] * v[j]) << i << " " << j;
        }
      }
    if (name == "eke") {  // Eq. (37), paper 001, by hand
      const double di = 60e-6, dj = 1000e-6;
      EXPECT_NEAR(beta[4],
                  std::exp(-17.24) * (di + dj) * (di + dj) * std::sqrt(1 / (di * di * di) + 1 / (dj * dj * dj)) * 0.22,
                  1e-12 * beta[4]);
    }
    if (name == "dem_collision") {  // Eqs. (12)-(13), paper 002: C = 10 / (1e3 1e3 0.5); wet if either LC >= 0.2
      EXPECT_EQ(beta[0], 0.0);
      EXPECT_NEAR(beta[1], 2e-5 * 0.01, 1e-20);
    }
  }
}

// efficiency_gradients (the engine's analytic Jacobian: one call per Jacobian, 2 m AD directions per pair) gives
// every kernel's E as efficiencies() does and dE/dphi as one evaluation per pair with the engine's Jets does, to the
// bit, and the derivatives are those of E (central differences).
TEST(PbmKernels, EfficiencyGradientsEqualThePairByPairDerivatives) {
  const auto g = Grid::from_diameter_pivots({60e-6, 120e-6, 250e-6, 500e-6, 1000e-6});
  set_table("test_collisions",
            collision_frequency_table(std::vector<double>(25, 10.0), std::vector<double>(5, 1e3), 0.5, "test"));
  std::vector<double> X{0.02, 0.05, 0.11, 0.07, 0.2}, T{320.0, 328.0, 335.0, 341.0, 350.0}, LC{0.1, 0.3, 0.1, 0.3, 0.5};
  ClassState<double> cs;
  cs.n = 5, cs.volume = g.pivots().data(), cs.diameter = g.diameter_pivots().data();
  cs.fields[0] = X.data(), cs.fields[1] = X.data(), cs.fields[2] = T.data(), cs.fields[3] = LC.data();
  cs.fields[4] = LC.data();
  int with_features = 0;
  for (const auto& name : registries().aggregation.names()) {
    auto k = registries().aggregation.create(name);
    Settings st("test", {{"agg_collisions", "test_collisions"}});
    k->declare(st, "agg_");
    std::vector<double> p;
    for (const auto& s : k->params()) p.push_back(s.value);
    const int m = k->n_features(), n = 5, pairs = n * (n + 1) / 2;
    std::vector<double> phi(size_t(n) * std::max(m, 1)), E(pairs), Eg(pairs), dEa(size_t(pairs) * m),
        dEb(size_t(pairs) * m);
    k->features(cs, p.data(), phi.data());
    k->efficiencies(phi.data(), n, p.data(), E.data());
    k->efficiency_gradients(phi.data(), n, p.data(), static_cast<int>(p.size()), Eg.data(), dEa.data(), dEb.data());
    with_features += m > 0;
    std::vector<Jet> pj(p.begin(), p.end());
    int q = 0;
    for (int i = 0; i < n; ++i)
      for (int j = i; j < n; ++j, ++q) {
        EXPECT_EQ(Eg[q], E[q]) << name << " " << i << " " << j;
        Jet a[kMaxFeatures], b[kMaxFeatures];
        for (int c = 0; c < m; ++c) {
          a[c] = Jet(phi[size_t(i) * m + c]), a[c].v[c] = 1.0;
          b[c] = Jet(phi[size_t(j) * m + c]), b[c].v[m + c] = 1.0;
        }
        const Jet e = m > 0 ? k->efficiency(a, b, pj.data()) : Jet(1.0);
        for (int c = 0; c < m; ++c) {
          EXPECT_EQ(dEa[q * m + c], e.v[c]) << name << " " << i << " " << j << " " << c;
          EXPECT_EQ(dEb[q * m + c], e.v[m + c]) << name << " " << i << " " << j << " " << c;
          std::vector<double> hi(phi.begin() + size_t(i) * m, phi.begin() + size_t(i) * m + m), lo = hi;
          const double h = 1e-6 * std::max(1.0, std::abs(hi[c]));
          hi[c] += h, lo[c] -= h;
          const double fd = (k->efficiency(hi.data(), &phi[size_t(j) * m], p.data()) -
                             k->efficiency(lo.data(), &phi[size_t(j) * m], p.data())) /
                            (2 * h);
          EXPECT_NEAR(dEa[q * m + c], fd, 1e-6 * std::max(1.0, std::abs(fd))) << name << " " << i << " " << j;
        }
      }
  }
  EXPECT_GT(with_features, 0);  // glass_transition and dem_collision have features
}

// The Python prototyping path: a callable returning the n x n matrix. It is state-independent, so it is
// evaluated once per run, however many residuals the solver takes.
TEST(PbmKernels, CallableKernelReproducesTheCompiledOneAndIsEvaluatedOncePerRun) {
  auto& reg = registries().aggregation;
  static int calls = 0;
  if (!reg.contains("test_python_constant"))
    register_callback_kernel(reg, "test_python_constant", "beta = beta0 from a callable",
                             {{"beta0", "1/s", 1.0, 0.0, 10.0, "rate coefficient", "test"}}, {},
                             [](const ClassState<double>& s, const double* p, double* beta) {
                               ++calls;
                               for (int k = 0; k < s.n * s.n; ++k) beta[k] = p[0];
                             });
  std::vector<double> m2;
  for (const char* k : {"constant", "test_python_constant"}) {
    auto s = pbm_test::grid_settings(2, 20);
    s["aggregation"] = k;
    auto fs = pbm_test::flowsheet(s, {{"agg_beta0", 0.7}});
    calls = 0;
    const auto r = pbm_test::run(*fs, {0, 10});
    if (std::string(k) == "test_python_constant") {
      EXPECT_EQ(calls, 1);
      EXPECT_GT(r.result.stats.residuals, 50);
    }
    m2.push_back(pbm_test::moment(pbm_test::grid(2, 20), r.N(1), 2));
  }
  EXPECT_NEAR(m2[1] / m2[0], 1.0, 1e-12);
}

TEST(PbmKernels, SensitivityToAKernelParameterEqualsFiniteDifferences) {
  auto s = pbm_test::grid_settings(2, 20);
  s["aggregation"] = "sum";
  auto make = [&](double b) { return pbm_test::flowsheet(s, {{"agg_beta0", b}}); };
  auto fs = make(1.0);
  SimOptions o;
  o.t_end = 1.0;
  o.t_out = {0, 1.0};
  o.rtol = 1e-9;
  o.atol = 1e-13;
  o.sensitivities = {"pbm.agg_beta0"};
  const auto r = simulate(*fs, o);
  const int n = r.n_states();
  const auto g = pbm_test::grid(2, 20);
  double sens_m0 = 0;
  for (int i = 0; i < g.size(); ++i) sens_m0 += r.sens[size_t(n) + i];
  // M0 = exp(-beta0 t) for the sum kernel: dM0/dbeta0 = -t M0 (the discrete M0 obeys it exactly).
  const double m0 = pbm_test::moment(g, &r.y[n], 0);
  EXPECT_NEAR(sens_m0 / (-1.0 * m0), 1.0, 1e-5);
  // Class by class against central differences of two more runs (the sensitivity of each N_i, not only their sum).
  const double h = 1e-4;
  auto final_state = [&](double b) {
    auto f = make(b);
    SimOptions q = o;
    q.sensitivities.clear();
    q.rtol = 1e-11;
    q.atol = 1e-15;
    // the reference on IDAS, whose answer moves smoothly with the parameter at this tolerance (an explicit method's
    // step sequence jumps with it, and the difference quotient multiplies that by 1 / h); the sensitivities
    // themselves come from the method auto chose (Adams: the sum kernel is not stiff)
    q.method = Method::kIda;
    return simulate(*f, q).y;
  };
  const auto up = final_state(1.0 + h), dn = final_state(1.0 - h);
  double smax = 0;
  for (int i = 0; i < g.size(); ++i) smax = std::max(smax, std::abs(r.sens[size_t(n) + i]));
  for (int i = 0; i < g.size(); ++i)
    EXPECT_NEAR(r.sens[size_t(n) + i], (up[size_t(n) + i] - dn[size_t(n) + i]) / (2 * h), 1e-5 * smax) << "N_" << i;
}

}  // namespace
}  // namespace granuflow
