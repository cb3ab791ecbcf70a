// Aggregation schemes are plugins: a scheme written outside the engine (two_point_scheme.hpp, registered by name from
// this test) runs populations with no edit to the engine, and must keep the discrete equations' conservation, give
// the fixed pivot's rates (the same placement, written independently), reach Scott's constant-kernel solution to the
// fixed pivot's accuracy, and have an analytic Jacobian equal to AD's. A kernel-parameter change refreshes only what
// depends on the kernel's values: the scheme's grid-only tables are built once, and a population whose parameter
// moved gives the same rates, bit for bit, as one built for the new value.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "granuflow/dae_system.hpp"
#include "kernels/population/population.hpp"
#include "kernels/registry.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"
#include "scene_helpers.hpp"
#include "two_point_scheme.hpp"

namespace granuflow {
namespace {

namespace an = pbm_analytic;
using pbm_test::Strings;
using test_scheme::TwoPointSplit;

Strings aggregation(const std::string& kernel, const std::string& scheme, int q, int doublings = 27) {
  TwoPointSplit::register_once();
  auto s = pbm_test::grid_settings(q, doublings);
  s["aggregation"] = kernel;
  s["aggregation_scheme"] = scheme;
  return s;
}

// -r of the residual (the rates) of pbm_batch at a random state.
std::vector<double> rates_at_random_state(Flowsheet& fs, int n, unsigned seed) {
  DaeSystem sys(fs);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> y(sys.size(), 0.0), yp(sys.size(), 0.0), r(sys.size());
  for (int i = 0; i < n; ++i) y[i] = u(rng);
  sys.residual(0, y.data(), yp.data(), r.data());
  for (double& v : r) v = -v;
  return r;
}

TEST(PbmSchemePlugin, RegisteredByNameFromTheTest) {
  TwoPointSplit::register_once();
  TwoPointSplit::register_once();  // once only
  const auto names = kernels::registries().aggregation_schemes.names();
  EXPECT_NE(std::find(names.begin(), names.end(), TwoPointSplit::kName), names.end());
}

// d/dt (sum N x + volume_above) = 0 and d/dt (sum N + number_above) = -1/2 sum_jk beta_jk N_j N_k, to round-off.
TEST(PbmSchemePlugin, DiscreteEquationsConserveVolumeAndNumberChangeToRoundOff) {
  for (const char* kernel : {"constant", "sum", "product"}) {
    auto fs = pbm_test::flowsheet(aggregation(kernel, TwoPointSplit::kName, 3, 10));
    const auto g = pbm_test::grid(3, 10);
    const int n = g.size();
    const auto rates = rates_at_random_state(*fs, n, 3);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> y(n);
    for (int i = 0; i < n; ++i) y[i] = u(rng);
    const int ia = fs->state_id("pbm.number_above"), iv = fs->state_id("pbm.volume_above");
    double dv = rates[iv], dv_scale = 0, dn = rates[ia], events = 0;
    for (int i = 0; i < n; ++i)
      dv += rates[i] * g.pivot(i), dv_scale += std::abs(rates[i]) * g.pivot(i), dn += rates[i];
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double vj = g.pivot(j), vk = g.pivot(k);
        const double beta = std::string(kernel) == "constant" ? 1.0 : std::string(kernel) == "sum" ? vj + vk : vj * vk;
        events += 0.5 * beta * y[j] * y[k];
      }
    EXPECT_NEAR(dv / dv_scale, 0.0, 1e-14) << kernel;
    EXPECT_NEAR(dn / events, -1.0, 1e-13) << kernel;
  }
}

// The same placement as the fixed pivot (Kumar & Ramkrishna 1996), summed pair by pair instead of by prefix sums and
// matrices: the rates agree to round-off, outside rows included.
TEST(PbmSchemePlugin, RatesEqualTheFixedPivots) {
  for (const char* kernel : {"constant", "sum", "product", "stokes"})
    for (const char* outside : {"fold", "remove"}) {
      auto settings = [&](const char* scheme) {
        auto s = aggregation(kernel, scheme, 2, 14);
        s["outside"] = outside;
        return s;
      };
      auto fs_test = pbm_test::flowsheet(settings(TwoPointSplit::kName));
      auto fs_fp = pbm_test::flowsheet(settings("fixed_pivot"));
      const int n = 28;
      const auto a = rates_at_random_state(*fs_test, n, 11), b = rates_at_random_state(*fs_fp, n, 11);
      ASSERT_EQ(a.size(), b.size());
      double scale = 0;
      for (double v : b) scale = std::max(scale, std::abs(v));
      for (size_t i = 0; i < a.size(); ++i)
        EXPECT_NEAR(a[i], b[i], 1e-13 * scale) << kernel << " " << outside << " " << i;
    }
}

// Scott's solution at tau = 100 on the q = 4 verification grid, to the fixed pivot's accuracy (its over-prediction of
// M2 included: the placement is the same), with volume kept along the run.
TEST(PbmSchemePlugin, ConstantKernelMatchesScottAtTau100) {
  const double tau = 100;
  auto fs = pbm_test::flowsheet(aggregation("constant", TwoPointSplit::kName, 4));
  const auto g = pbm_test::grid(4);
  const auto r = pbm_test::run(*fs, {0, 1, 10, tau});
  for (size_t k = 0; k < r.result.t.size(); ++k)
    EXPECT_NEAR(pbm_test::moment(g, r.N(k), 0) / an::scott_m0(r.result.t[k]), 1.0, 3e-4) << r.result.t[k];
  EXPECT_NEAR(pbm_test::moment(g, r.N(3), 2) / an::scott_m2(tau), 1.0, 1.6e-2);
  const auto exact = an::cell_volumes(g, [&](double v) { return an::scott_density(v, tau); });
  EXPECT_LT(an::l1_mass_error(g, r.N(3), exact), 0.015);
  const double v0 = pbm_test::moment(g, r.N(0), 1);
  for (size_t k = 0; k < r.result.t.size(); ++k)
    EXPECT_NEAR((pbm_test::moment(g, r.N(k), 1) + r.state(k, "volume_above")) / v0, 1.0, 1e-12);
}

// The scheme's Jacobian hook against forward AD of the whole residual (which runs the scheme's Jet rates).
TEST(PbmSchemePlugin, AnalyticJacobianEqualsAd) {
  for (const char* outside : {"fold", "remove"}) {
    auto s = aggregation("sum", TwoPointSplit::kName, 2, 12);
    s["outside"] = outside;
    auto fs = pbm_test::flowsheet(s);
    DaeSystem sys(*fs);
    const int n = sys.size();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.2, 1.0);
    std::vector<double> y(n), yp(n), dense(size_t(n) * n), ad(size_t(n) * n);
    sys.initial_values(y);
    for (int i = 0; i < n; ++i) y[i] = std::abs(y[i]) * u(rng) + 1e-3 * u(rng), yp[i] = 0.1 * u(rng);
    sys.jacobian(0.0, y.data(), yp.data(), 2.5, dense.data(), nullptr);
    sys.reference_jacobian(0.0, y.data(), yp.data(), 2.5, ad.data());
    double scale = 0;
    for (double v : ad) scale = std::max(scale, std::abs(v));
    for (size_t i = 0; i < ad.size(); ++i) ASSERT_NEAR(dense[i], ad[i], 1e-11 * scale) << outside << " entry " << i;
  }
}

// A population declared with `settings` on a geometric grid of n classes, its parameters at their defaults.
struct Pop {
  kernels::Population pop;
  std::vector<double> p;
  kernels::Population::WorkPtr w;
  Pop(const std::map<std::string, std::string>& settings, int n, int properties) {
    UnitSpec spec;
    Settings st("test", settings);
    kernels::PopulationOptions o;
    for (int k = 0; k < properties; ++k) o.properties.push_back("q" + std::to_string(k));
    pop.declare(spec, st, std::make_shared<const kernels::Grid>(kernels::Grid::geometric(1e-12, 2, n)), o);
    for (const auto& ps : spec.params()) p.push_back(ps.value);
    w = pop.make_work();
  }
  // The rates (class rows, properties, outside rows) at a random state with fields.
  std::vector<double> rates(unsigned seed) {
    const int n = pop.size(), P = pop.properties();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> N(n), fields[kernels::kFields], floor(n, 1e-9), out(size_t(n) * (1 + P) + pop.outside_rows());
    std::vector<std::vector<double>> q(P, std::vector<double>(n));
    for (int i = 0; i < n; ++i) N[i] = 0.1 + u(rng);
    for (auto& f : fields)
      for (int i = 0; i < n; ++i) f.push_back(0.05 + 0.3 * u(rng));
    fields[int(kernels::Field::kTemperature)].assign(n, 330.0);
    for (auto& qk : q)
      for (int i = 0; i < n; ++i) qk[i] = N[i] * u(rng);
    kernels::Population::State<double> s;
    kernels::Population::Rates<double> r;
    s.N = N.data(), s.floor = floor.data(), s.p = p.data(), r.dN = out.data();
    for (int f = 0; f < kernels::kFields; ++f) s.fields[f] = fields[f].data();
    for (int k = 0; k < P; ++k) s.q[k] = q[k].data(), r.dq[k] = out.data() + size_t(n) * (1 + k);
    r.outside = out.data() + size_t(n) * (1 + P);
    pop.rates(*w, s, r);
    return out;
  }
};

TEST(PbmSchemePlugin, ParameterChangeRefreshesOnlyTheKernelsTables) {
  TwoPointSplit::register_once();
  const int setups = TwoPointSplit::setups, refreshes = TwoPointSplit::refreshes;
  Pop a({{"aggregation", "constant"}, {"aggregation_scheme", TwoPointSplit::kName}}, 20, 1);
  EXPECT_EQ(TwoPointSplit::setups, setups + 1);  // declare(): the grid-only tables
  a.pop.configure(*a.w, a.p.data(), "test");
  EXPECT_EQ(TwoPointSplit::refreshes, refreshes + 1);
  a.rates(1);
  EXPECT_EQ(TwoPointSplit::refreshes, refreshes + 1);  // same parameters: nothing rebuilt
  a.p[0] = 2.5;                                        // beta0
  a.rates(1);
  EXPECT_EQ(TwoPointSplit::refreshes, refreshes + 2);
  EXPECT_EQ(TwoPointSplit::setups, setups + 1);
}

// Every evaluation path of the built-in schemes (separable prefix sums, pair matrices, rows with efficiencies), with
// and without carried properties: rates after a parameter change inside a run equal, bit for bit, those of a
// population configured for the new value.
TEST(PbmSchemePlugin, RatesAfterAParameterChangeEqualAFreshPopulations) {
  struct Case {
    const char* kernel;
    int properties;
    const char* path;
  };
  for (const char* scheme : {"fixed_pivot", "cell_average"})
    for (const Case& c :
         {Case{"constant", 0, "separable"}, Case{"sum", 0, "separable"}, Case{"constant", 1, "matrices"},
          Case{"stokes", 0, "matrices"}, Case{"glass_transition", 1, "pairs"}, Case{"glass_transition", 2, "pairs"}}) {
      const std::map<std::string, std::string> settings{{"aggregation", c.kernel}, {"aggregation_scheme", scheme}};
      Pop moved(settings, 24, c.properties), fresh(settings, 24, c.properties);
      moved.pop.configure(*moved.w, moved.p.data(), "test");
      ASSERT_EQ(moved.pop.aggregation_evaluation(*moved.w), c.path) << scheme << " " << c.kernel;
      moved.rates(5);
      moved.p[0] = fresh.p[0] = moved.p[0] * 1.5 + 0.25;
      fresh.pop.configure(*fresh.w, fresh.p.data(), "test");
      const auto a = moved.rates(5), b = fresh.rates(5);
      for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << scheme << " " << c.kernel << " row " << i;
    }
}

}  // namespace
}  // namespace granuflow
