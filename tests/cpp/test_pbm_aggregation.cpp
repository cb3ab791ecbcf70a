// Aggregation on the grid against the analytic solutions of docs/verification.md (N0 = v0 = 1, n(v, 0) = exp(-v)):
// constant (Scott), sum (Golovin) and product kernels; discrete conservation of number change and volume to
// round-off; observed convergence order of the fixed pivot under grid refinement.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <type_traits>

#include "granuflow/dae_system.hpp"
#include "kernels/population/population.hpp"
#include "kernels/registry.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"

namespace granuflow {
namespace {

namespace an = pbm_analytic;
using pbm_test::Strings;

Strings aggregation(const std::string& kernel, const std::string& scheme, int q, int doublings = 27) {
  auto s = pbm_test::grid_settings(q, doublings);
  s["aggregation"] = kernel;
  s["aggregation_scheme"] = scheme;
  return s;
}

// The error of the solution at t_end on the q = 2, 4, 8 verification grids (each refinement halves log2 of the
// grid ratio), from error(grid, N).
std::vector<double> refinement_errors(const std::string& kernel, const std::string& scheme, double t_end,
                                      const std::function<double(const kernels::Grid&, const double*)>& error) {
  std::vector<double> err;
  for (int q : {2, 4, 8}) {
    auto fs = pbm_test::flowsheet(aggregation(kernel, scheme, q));
    const auto r = pbm_test::run(*fs, {0, t_end}, 1e-8, 1e-12);
    err.push_back(error(pbm_test::grid(q), r.N(1)));
  }
  return err;
}

// Volume and number bookkeeping along a run: sum N x + volume_above = its initial value (round-off), and
// number_above never negative.
void expect_bookkeeping(const pbm_test::Run& r, const kernels::Grid& g) {
  const double v0 = pbm_test::moment(g, r.N(0), 1);
  for (size_t k = 0; k < r.result.t.size(); ++k) {
    const double v = pbm_test::moment(g, r.N(k), 1) + r.state(k, "volume_above");
    EXPECT_NEAR(v / v0 - 1.0, 0.0, 1e-12) << "t = " << r.result.t[k];
    EXPECT_GE(r.state(k, "number_above"), -1e-15);
  }
}

// The discrete equations themselves, at random states: d/dt (sum N x + volume_above) = 0 and
// d/dt (sum N + number_above) = -1/2 sum_jk beta_jk N_j N_k, for both schemes and three kernels.
TEST(PbmAggregation, DiscreteEquationsConserveVolumeAndNumberChangeToRoundOff) {
  for (const char* scheme : {"cell_average", "fixed_pivot"})
    for (const char* kernel : {"constant", "sum", "product"}) {
      auto fs = pbm_test::flowsheet(aggregation(kernel, scheme, 3, 10));
      const auto g = pbm_test::grid(3, 10);
      DaeSystem sys(*fs);
      const int n = g.size(), ns = sys.size();
      std::mt19937 rng(3);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      std::vector<double> y(ns, 0.0), yp(ns, 0.0), r(ns);
      for (int i = 0; i < n; ++i) y[i] = u(rng);
      sys.residual(0, y.data(), yp.data(), r.data());  // r = -rates
      const int ia = fs->state_id("pbm.number_above"), iv = fs->state_id("pbm.volume_above");
      double dv = -r[iv], dv_scale = 0, dn = -r[ia], events = 0;
      for (int i = 0; i < n; ++i) dv -= r[i] * g.pivot(i), dv_scale += std::abs(r[i]) * g.pivot(i), dn -= r[i];
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const double vj = g.pivot(j), vk = g.pivot(k);
          const double beta = std::string(kernel) == "constant" ? 1.0
                              : std::string(kernel) == "sum"    ? vj + vk
                                                                : vj * vk;
          events += 0.5 * beta * y[j] * y[k];
        }
      EXPECT_NEAR(dv / dv_scale, 0.0, 1e-14) << scheme << " " << kernel;
      EXPECT_NEAR(dn / events, -1.0, 1e-13) << scheme << " " << kernel;
    }
}

TEST(PbmAggregation, ConstantKernelMatchesScottAtTau100) {
  const double tau = 100;
  struct Case {
    const char* scheme;
    int q;
    double m2_tol, l1_tol;
  };
  // Measured M2 errors (L1 of the mass density): cell_average q=1 +2.0e-3 (0.095), q=4 -4.6e-4 (0.0056);
  // fixed_pivot q=4 +1.45e-2 (0.011), its known over-prediction.
  for (const Case& c : {Case{"cell_average", 1, 3e-3, 0.12}, Case{"cell_average", 4, 6e-4, 0.008},
                        Case{"fixed_pivot", 4, 1.6e-2, 0.015}}) {
    auto fs = pbm_test::flowsheet(aggregation("constant", c.scheme, c.q));
    const auto g = pbm_test::grid(c.q);
    const auto r = pbm_test::run(*fs, {0, 1, 10, tau});
    for (size_t k = 0; k < r.result.t.size(); ++k) {
      const double t = r.result.t[k];
      // M0 is exact in the discrete equations (beta = 1: dM0/dt = -M0^2/2); only the mass below the grid
      // (2.4e-4 of the number at t = 0) and the integration tolerance remain.
      EXPECT_NEAR(pbm_test::moment(g, r.N(k), 0) / an::scott_m0(t), 1.0, 3e-4) << c.scheme << " t = " << t;
    }
    const double m2 = pbm_test::moment(g, r.N(3), 2);
    EXPECT_NEAR(m2 / an::scott_m2(tau), 1.0, c.m2_tol) << c.scheme << " q = " << c.q;
    const auto exact = an::cell_volumes(g, [&](double v) { return an::scott_density(v, tau); });
    const double l1 = an::l1_mass_error(g, r.N(3), exact);
    EXPECT_LT(l1, c.l1_tol) << c.scheme << " q = " << c.q;
    std::printf("%s q=%d: M2 err %.3e, L1 %.3e\n", c.scheme, c.q, m2 / an::scott_m2(tau) - 1, l1);
    expect_bookkeeping(r, g);
  }
}

TEST(PbmAggregation, SumKernelMatchesGolovinAtT3) {
  const double T = 3;
  for (const char* scheme : {"cell_average", "fixed_pivot"}) {
    auto fs = pbm_test::flowsheet(aggregation("sum", scheme, 4));
    const auto g = pbm_test::grid(4);
    const auto r = pbm_test::run(*fs, {0, 1, T});
    // M0 = exp(-T): exact in the discrete equations too (dM0/dt = -M0 M1, M1 conserved).
    EXPECT_NEAR(pbm_test::moment(g, r.N(2), 0) / an::golovin_m0(T), 1.0, 1e-3) << scheme;
    const double err = pbm_test::moment(g, r.N(2), 2) / an::golovin_m2(T) - 1.0;
    // Measured: cell_average -1.1e-2; fixed_pivot +0.214 (over-prediction grows with the kernel's reach).
    if (std::string(scheme) == "cell_average")
      EXPECT_LT(std::abs(err), 0.02);
    else
      EXPECT_NEAR(err, 0.214, 0.01);
    const auto exact = an::cell_volumes(g, [&](double v) { return an::golovin_density(v, T); });
    EXPECT_LT(an::l1_mass_error(g, r.N(2), exact), std::string(scheme) == "cell_average" ? 0.03 : 0.15) << scheme;
    expect_bookkeeping(r, g);
  }
}

TEST(PbmAggregation, ProductKernelMatchesMomentsBeforeGelation) {
  const double tau = 0.4;  // M2 = 10
  auto fs = pbm_test::flowsheet(aggregation("product", "cell_average", 4));
  const auto g = pbm_test::grid(4);
  const auto r = pbm_test::run(*fs, {0, 0.2, tau});
  for (size_t k = 1; k < 3; ++k) {
    const double t = r.result.t[k];
    EXPECT_NEAR(pbm_test::moment(g, r.N(k), 0) / an::product_m0(t), 1.0, 1e-3) << "t = " << t;
    EXPECT_NEAR(pbm_test::moment(g, r.N(k), 2) / an::product_m2(t), 1.0, 0.02) << "t = " << t;
  }
  expect_bookkeeping(r, g);
}

// Fixed pivot, constant kernel, tau = 100: the M2 error falls as 1/q^2 (second order in the grid ratio's
// logarithm). Measured errors 6.07e-2, 1.45e-2, 3.58e-3 for q = 2, 4, 8.
TEST(PbmAggregation, FixedPivotConvergesAtSecondOrderUnderRefinement) {
  const auto err = refinement_errors("constant", "fixed_pivot", 100, [](const kernels::Grid& g, const double* N) {
    return std::abs(pbm_test::moment(g, N, 2) / an::scott_m2(100) - 1.0);
  });
  for (size_t k = 1; k < err.size(); ++k) {
    const double order = std::log2(err[k - 1] / err[k]);
    EXPECT_GT(order, 1.8) << "refinement " << k;
    EXPECT_LT(order, 2.3) << "refinement " << k;
  }
}

// Cell average, sum kernel, T = 3: the L1 error of the mass density falls at least at first order.
TEST(PbmAggregation, CellAverageDensityConvergesUnderRefinement) {
  const auto err = refinement_errors("sum", "cell_average", 3, [](const kernels::Grid& g, const double* N) {
    return an::l1_mass_error(g, N, an::cell_volumes(g, [](double v) { return an::golovin_density(v, 3); }));
  });
  for (size_t k = 1; k < err.size(); ++k)
    EXPECT_GT(std::log2(err[k - 1] / err[k]), 0.9) << "errors " << err[k - 1] << " " << err[k];
}

// Outside = fold (paper 001): aggregates beyond the top stay in the last class with their volume; the volume
// that went there is reported and the on-grid volume is conserved to round-off.
TEST(PbmAggregation, FoldKeepsVolumeOnTheGridAndReportsIt) {
  auto s = aggregation("constant", "cell_average", 2, 8);  // v < 2^-4: the grid fills up quickly
  s["outside"] = "fold";
  auto fs = pbm_test::flowsheet(s, {{"v0", 0.01}});
  const auto g = pbm_test::grid(2, 8);
  const auto r = pbm_test::run(*fs, {0, 50});
  const double v0 = pbm_test::moment(g, r.N(0), 1);
  EXPECT_NEAR(pbm_test::moment(g, r.N(1), 1) / v0, 1.0, 1e-12);
  EXPECT_GT(r.state(1, "volume_above"), 0.01 * v0);  // a substantial part went past the top and was folded
  EXPECT_NEAR(r.output(1, "mass_balance"), 0.0, 1e-12);
}

namespace separable {

using kernels::Grid;
using kernels::Population;

// One engine evaluation of a random state with empty classes, in doubles (the kernel's fast path) and in Jets (the
// pair loop over every pair, the reference), and the scale of each rate.
struct Evaluation {
  std::string path;
  std::vector<double> fast, loop, scale;  // class rows, then the outside rows
};

Evaluation evaluate(const std::string& kernel, const std::string& scheme, const std::string& outside,
                    std::shared_ptr<const Grid> g, unsigned seed) {
  UnitSpec spec;
  Settings st("test", {{"aggregation", kernel}, {"aggregation_scheme", scheme}, {"outside", outside}});
  Population pop;
  pop.declare(spec, st, g, {});
  std::vector<double> p;
  for (const auto& s : spec.params()) p.push_back(s.value);
  auto w = pop.make_work();
  pop.configure(*w, p.data(), "test");
  const int n = pop.size(), no = pop.outside_rows();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> N(n);
  for (int i = 0; i < n; ++i) N[i] = u(rng) < 0.15 ? 0.0 : u(rng) * std::exp(-0.01 * g->pivot(i));
  Evaluation e;
  e.path = pop.aggregation_evaluation(*w);
  e.fast.assign(n + no, 0.0);
  Population::State<double> s;
  s.N = N.data(), s.p = p.data();
  Population::Rates<double> r;
  r.dN = e.fast.data(), r.outside = e.fast.data() + n;
  pop.rates(*w, s, r);
  std::vector<Jet> NJ(N.begin(), N.end()), pJ(p.begin(), p.end()), out(n + no, Jet(0.0));
  Population::State<Jet> sj;
  sj.N = NJ.data(), sj.p = pJ.data();
  Population::Rates<Jet> rj;
  rj.dN = out.data(), rj.outside = out.data() + n;
  pop.rates(*w, sj, rj);
  for (const Jet& v : out) e.loop.push_back(v.a);
  auto k = kernels::registries().aggregation.create(kernel, "test");
  kernels::ClassState<double> cs;
  cs.n = n, cs.volume = g->pivots().data(), cs.diameter = g->diameter_pivots().data();
  std::vector<double> K(size_t(n) * n);
  k->factor(cs, p.data(), K.data());
  // the events of every pair that can place an aggregate in class i (both partners <= i) and the deaths of class i
  e.scale.assign(n + no, 0.0);
  double below = 0, total = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) below += K[size_t(i) * n + j] * N[i] * N[j];
    double deaths = 0;
    for (int j = 0; j < n; ++j) deaths += K[size_t(i) * n + j] * N[i] * N[j];
    e.scale[i] = below + deaths;
    total += e.scale[i] * g->pivot(i);
  }
  for (int i = n; i < n + no; ++i) e.scale[i] = total;  // the outside rows hold volumes and numbers
  return e;
}

}  // namespace separable

// Kernels with a separable size factor (constant, sum, product) sum aggregation with prefix sums (O(n) per term)
// instead of the pair table: on geometric grids of 1 to 4 classes per volume doubling, both schemes, both outside
// rules, and on an irregular grid, the rates equal those of the loop over every pair to round-off, the outside rows
// included.
TEST(PbmAggregation, SeparableKernelsGiveThePairLoopsRates) {
  for (int q : {1, 2, 3, 4}) {
    const auto g = std::make_shared<const kernels::Grid>(kernels::Grid::geometric(std::exp2(-12.0), q, 14 * q));
    for (const char* kernel : {"constant", "sum", "product"})
      for (const char* scheme : {"fixed_pivot", "cell_average"})
        for (const char* outside : {"fold", "remove"}) {
          const auto e = separable::evaluate(kernel, scheme, outside, g, 7u + q);
          ASSERT_EQ(e.path, "separable") << kernel << " " << scheme << " q=" << q;
          for (size_t i = 0; i < e.fast.size(); ++i)
            EXPECT_NEAR(e.fast[i], e.loop[i], 1e-13 * e.scale[i] + 1e-300)
                << kernel << " " << scheme << " " << outside << " q=" << q << " row " << i;
        }
  }
  // An irregular grid (edges growing by ratios between 1.3 and 2.6): the near-equal partners no longer line up along
  // diagonals, so more pairs are summed one by one, and the prefixes must still hold exactly the run pairs.
  std::vector<double> edges{1e-3};
  for (int i = 0; i < 40; ++i) edges.push_back(edges.back() * (1.3 + 1.3 * std::abs(std::sin(1.7 * i))));
  const auto g = std::make_shared<const kernels::Grid>(kernels::Grid::from_edges(edges));
  for (const char* kernel : {"constant", "sum", "product"})
    for (const char* scheme : {"fixed_pivot", "cell_average"}) {
      const auto e = separable::evaluate(kernel, scheme, "remove", g, 5u);
      EXPECT_EQ(e.path, "separable") << kernel << " " << scheme << " (irregular grid)";
      for (size_t i = 0; i < e.fast.size(); ++i)
        EXPECT_NEAR(e.fast[i], e.loop[i], 1e-13 * e.scale[i] + 1e-300)
            << kernel << " " << scheme << " (irregular grid) row " << i;
    }
}

// A kernel with per-pair efficiencies (paper 001's glass-transition kernel, reading wetted fraction, spot moisture and
// temperature per class) aggregates row by row over the pair triangle; in doubles the fixed-pivot rows fuse rates,
// deaths and births in one pass (with AVX-512, 8 partners at a time and a masked last step). On grids of 2 to 25
// classes, so that rows end on every remainder of 8, with one carried property and with two, and with both outside
// rules, the rates equal those of the Jet path, which places every pair on its own, to round-off: a partner skipped
// or counted twice at the end of a row moves a rate by a whole event.
TEST(PbmAggregation, FusedFixedPivotRowsGiveThePairLoopsRates) {
  using kernels::Population;
  for (int n = 2; n <= 25; ++n) {
    const auto g = std::make_shared<const kernels::Grid>(kernels::Grid::geometric(1e-12, 2, n));
    for (int P : {1, 2})
      for (const char* outside : {"fold", "remove"}) {
        UnitSpec spec;
        Settings st("test",
                    {{"aggregation", "glass_transition"}, {"aggregation_scheme", "fixed_pivot"}, {"outside", outside}});
        kernels::PopulationOptions o;
        o.properties = P == 1 ? std::vector<std::string>{"water"} : std::vector<std::string>{"water", "binder"};
        Population pop;
        pop.declare(spec, st, g, o);
        std::vector<double> p;
        for (const auto& ps : spec.params()) p.push_back(ps.value);
        p[0] = 20.0;  // ln beta0 (the kernel's first parameter): rates of order one for numbers of order one
        auto w = pop.make_work();
        pop.configure(*w, p.data(), "test");
        ASSERT_EQ(pop.aggregation_evaluation(*w), "pairs");
        const int no = pop.outside_rows();
        std::mt19937 rng(100u * n + P);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::vector<double> N(n), fw(n), xs(n), T(n), floor(n, 1e-9);  // floor: an empty class carries 0
        std::vector<std::vector<double>> q(P, std::vector<double>(n));
        for (int i = 0; i < n; ++i) {
          N[i] = i > 0 && u(rng) < 0.15 ? 0.0 : 0.1 + u(rng);  // an empty class now and then
          for (int k = 0; k < P; ++k) q[k][i] = N[i] * (0.01 + u(rng));
          fw[i] = u(rng), xs[i] = 0.3 * u(rng), T[i] = 300.0 + 40.0 * u(rng);
        }
        // The rates in scalar type Scalar (double: the fused rows; Jet: every pair placed on its own), value parts.
        auto rates = [&](auto zero) {
          using Scalar = decltype(zero);
          auto in = [](const std::vector<double>& v) { return std::vector<Scalar>(v.begin(), v.end()); };
          auto NT = in(N), pT = in(p), fwT = in(fw), xsT = in(xs), TT = in(T), floorT = in(floor);
          std::vector<std::vector<Scalar>> qT;
          for (int k = 0; k < P; ++k) qT.push_back(in(q[k]));
          std::vector<Scalar> out(size_t(n) * (1 + P) + no, zero);
          Population::State<Scalar> s;
          Population::Rates<Scalar> r;
          s.N = NT.data(), s.floor = floorT.data(), s.p = pT.data(), r.dN = out.data();
          r.outside = out.data() + n * (1 + P);
          s.fields[int(kernels::Field::kWettedFraction)] = fwT.data();
          s.fields[int(kernels::Field::kSpotMoisture)] = xsT.data();
          s.fields[int(kernels::Field::kTemperature)] = TT.data();
          for (int k = 0; k < P; ++k) s.q[k] = qT[k].data(), r.dq[k] = out.data() + n * (1 + k);
          pop.rates(*w, s, r);
          std::vector<double> values;
          for (const Scalar& v : out) values.push_back(value_of(v));
          return values;
        };
        const std::vector<double> fast = rates(0.0), loop = rates(Jet(0.0));

        // every rate is a sum of events of at most sum_jk K_jk N_j N_k (efficiencies <= 1) times a carried
        // property of order one: the scale of its round-off
        auto k = kernels::registries().aggregation.create("glass_transition", "test");
        kernels::ClassState<double> cs;
        cs.n = n, cs.volume = g->pivots().data(), cs.diameter = g->diameter_pivots().data();
        std::vector<double> K(size_t(n) * n);
        k->factor(cs, p.data(), K.data());
        double events = 0.0;
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) events += K[size_t(i) * n + j] * N[i] * N[j];
        ASSERT_GT(events, 1e-3) << "n=" << n;
        for (size_t i = 0; i < fast.size(); ++i)
          EXPECT_NEAR(fast[i], loop[i], 1e-14 * events * (i < size_t(n) || i >= size_t(n) * (1 + P) ? 1.0 : 2.0))
              << "n=" << n << " P=" << P << " " << outside << " row " << i;
      }
  }
}

// The engine's analytic Jacobian of fixed-pivot aggregation carrying two properties (the general property count of
// FixedPivotAggregation::jacobian_row) against forward AD of its rates, column by column: numbers, properties and
// the glass-transition kernel's three fields of every class.
TEST(PbmAggregation, FixedPivotJacobianWithTwoPropertiesEqualsForwardAd) {
  using kernels::Field;
  using kernels::Population;
  struct DenseSink : JacobianSink {
    DenseSink(double* d, size_t ld) : JacobianSink(d, ld) {}
  };
  const int n = 9, P = 2, nf = 3;
  // two classes per doubling of volume: most pairs land between two pivots
  const auto g = std::make_shared<const kernels::Grid>(kernels::Grid::geometric(1e-12, 2, n));
  UnitSpec spec;
  Settings st("test",
              {{"aggregation", "glass_transition"}, {"aggregation_scheme", "fixed_pivot"}, {"outside", "fold"}});
  kernels::PopulationOptions o;
  o.properties = {"water", "binder"};
  Population pop;
  pop.declare(spec, st, g, o);
  std::vector<double> p;
  for (const auto& ps : spec.params()) p.push_back(ps.value);
  p[0] = 5.0;  // ln beta0: rates of order one
  auto w = pop.make_work();
  pop.configure(*w, p.data(), "test");
  // inputs: N, q_0, q_1, then wetted fraction, spot moisture, temperature per class; rows: N, q_0, q_1
  const Field fields[nf] = {Field::kWettedFraction, Field::kSpotMoisture, Field::kTemperature};
  const int R = n * (1 + P), C = R + nf * n;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x(C), floor(n, 1e-9);
  for (int i = 0; i < n; ++i) {
    x[i] = 0.2 + u(rng);
    for (int k = 0; k < P; ++k) x[n * (1 + k) + i] = x[i] * (0.01 + 0.2 * u(rng));
    x[R + i] = u(rng), x[R + n + i] = 0.3 * u(rng), x[R + 2 * n + i] = 300.0 + 40.0 * u(rng);
  }
  auto state = [&](auto* v, auto* fl, auto* pv) {
    Population::State<std::remove_pointer_t<decltype(v)>> s;
    s.N = v, s.floor = fl, s.p = pv;
    for (int k = 0; k < P; ++k) s.q[k] = v + n * (1 + k);
    for (int f = 0; f < nf; ++f) s.fields[static_cast<int>(fields[f])] = v + R + f * n;
    return s;
  };
  Population::Map m;
  m.q_factor = 1.0;
  m.q_col.assign(P, {}), m.q_row.assign(P, {});
  for (int i = 0; i < n; ++i) {
    m.N_col.push_back(i), m.N_row.push_back(i), m.N_scale.push_back(1.0), m.N_factor.push_back(1.0);
    for (int k = 0; k < P; ++k) m.q_col[k].push_back(n * (1 + k) + i), m.q_row[k].push_back(n * (1 + k) + i);
    for (int f = 0; f < nf; ++f) m.field_col[static_cast<int>(fields[f])].push_back(R + f * n + i);
  }
  std::vector<double> J(size_t(R) * C, 0.0);
  DenseSink sink(J.data(), R);
  pop.jacobian(*w, state(x.data(), floor.data(), p.data()), m, sink);
  for (int c = 0; c < C; ++c) {
    std::vector<Jet> xj(x.begin(), x.end()), fj(floor.begin(), floor.end()), pj(p.begin(), p.end()), out(R, Jet(0.0));
    xj[c].v[0] = 1.0;
    Population::Rates<Jet> r;
    r.dN = out.data();
    for (int k = 0; k < P; ++k) r.dq[k] = out.data() + n * (1 + k);
    pop.rates(*w, state(xj.data(), fj.data(), pj.data()), r);
    double colmax = 0.0;
    for (int row = 0; row < R; ++row) colmax = std::max(colmax, std::abs(out[row].v[0]));
    for (int row = 0; row < R; ++row)
      EXPECT_NEAR(J[size_t(c) * R + row], out[row].v[0], 1e-13 * colmax + 1e-14)  // floor: a folded column cancels
          << "row " << row << " column " << c;
  }
}

// Kernels without a separable factor, or populations carrying properties, keep the pair matrices.
TEST(PbmAggregation, KernelsWithoutSeparableFactorKeepThePairMatrices) {
  const auto g = std::make_shared<const kernels::Grid>(kernels::Grid::geometric(std::exp2(-12.0), 2, 28));
  const auto e = separable::evaluate("stokes", "fixed_pivot", "remove", g, 3u);
  EXPECT_EQ(e.path, "matrices");
  for (size_t i = 0; i < e.fast.size(); ++i) EXPECT_NEAR(e.fast[i], e.loop[i], 1e-13 * e.scale[i] + 1e-300) << i;
}

}  // namespace
}  // namespace granuflow
