// Aggregation on the grid against the analytic solutions of docs/verification.md (N0 = v0 = 1, n(v, 0) = exp(-v)):
// constant (Scott), sum (Golovin) and product kernels; discrete conservation of number change and volume to
// round-off; observed convergence order of the fixed pivot under grid refinement.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "granuflow/dae_system.hpp"
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

}  // namespace
}  // namespace granuflow
